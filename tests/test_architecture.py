"""The package's shape: at most 15 entries at the top of weather_mi/ (modules and subpackages, one per
concept), no import cycles (an AST walk of every import, at module level or inside functions), modules of at
most 600 lines, functions of at most 80 code lines unless a ``# long:`` comment on the line above the ``def``
gives the reason."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = {"weather_mi": ROOT / "weather_mi"}  # the Mitsuba plugins live inside, in weather_mi/kernel/plugins
MAX_MODULE_LINES = 600
MAX_TOP_LEVEL_ENTRIES = 15
MAX_FUNCTION_CODE_LINES = 80
LONG_MARKER = "# long:"


def modules(packages: dict[str, Path]) -> dict[str, tuple[Path, bool]]:
    """Dotted module name -> (file, is a package __init__)."""
    out = {}
    for pkg, root in packages.items():
        for path in sorted(root.rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            is_init = parts[-1] == "__init__"
            if is_init:
                parts = parts[:-1]
            out[".".join([pkg, *parts])] = (path, is_init)
    return out


def _owner(name: str, mods) -> str | None:
    """The module of ours that ``name`` (a module or a module.attribute) lives in, or None."""
    while name and name not in mods:
        name = name.rpartition(".")[0]
    return name or None


def import_graph(packages: dict[str, Path]) -> dict[str, set[str]]:
    """Edges module -> modules of ours it imports. ``from pkg import name`` points at the submodule
    ``pkg.name`` when there is one, else at ``pkg`` (the name comes from its __init__)."""
    mods = modules(packages)
    edges: dict[str, set[str]] = {m: set() for m in mods}
    for mod, (path, is_init) in mods.items():
        here = mod.split(".") if is_init else mod.split(".")[:-1]
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    base = ".".join(here[:len(here) - node.level + 1] + ([node.module] if node.module else []))
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in mods else base for a in node.names]
            for t in targets:
                owner = _owner(t, mods)
                if owner and owner != mod:
                    edges[mod].add(owner)
    return edges


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan, iterative)."""
    index, low, on_stack, stack, out, counter = {}, {}, set(), [], [], [0]
    for start in edges:
        if start in index:
            continue
        work = [(start, iter(sorted(edges[start])))]
        index[start] = low[start] = counter[0]
        counter[0] += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(edges[w]))))
                elif w in on_stack:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return out


def code_lines(node: ast.AST, lines: list[str]) -> int:
    """Lines of a function that hold code: its docstring, blank and comment-only lines excluded."""
    doc = set()
    first = node.body[0]
    if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(first.value.value, str):
        doc = set(range(first.lineno, first.end_lineno + 1))
    return sum(1 for i in range(node.lineno, node.end_lineno + 1)
               if i not in doc and lines[i - 1].strip() and not lines[i - 1].strip().startswith("#"))


def _shown(path: Path) -> str:
    return str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path)


def long_functions(packages: dict[str, Path]) -> list[str]:
    """Functions over the limit without a ``# long:`` reason on the line above their ``def``."""
    out = []
    for mod, (path, _) in modules(packages).items():
        lines = path.read_text().splitlines()
        for node in ast.walk(ast.parse("\n".join(lines), str(path))):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            n = code_lines(node, lines)
            top = min([node.lineno] + [d.lineno for d in node.decorator_list])
            reason = top >= 2 and lines[top - 2].strip().startswith(LONG_MARKER)
            if n > MAX_FUNCTION_CODE_LINES and not reason:
                out.append(f"{_shown(path)}:{node.lineno} {node.name} ({n} code lines)")
    return out


def top_level_entries(root: Path) -> list[str]:
    """The modules and subpackages at the top of a package (its ``__init__.py`` counted)."""
    return sorted(p.name for p in root.iterdir()
                  if (p.suffix == ".py") or (p.is_dir() and (p / "__init__.py").exists()))


def test_the_top_level_is_at_most_15_entries():
    found = top_level_entries(PACKAGES["weather_mi"])
    assert len(found) <= MAX_TOP_LEVEL_ENTRIES, f"{len(found)} entries at the top of weather_mi/: {found}"


def test_the_top_level_count_sees_modules_and_packages(tmp_path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "__init__.py").write_text("")
    (tmp_path / "data").mkdir()  # not a package
    for name in ("__init__.py", "a.py", "notes.md"):
        (tmp_path / name).write_text("")
    assert top_level_entries(tmp_path) == ["__init__.py", "a.py", "sub"]


def test_no_import_cycles():
    found = cycles(import_graph(PACKAGES))
    assert not found, "import cycles (every arrow must point down io -> optics -> scene -> renderers -> " \
                      f"metrics -> study/viewer/cli): {found}"


def test_the_cycle_check_fails_on_an_added_cycle(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("from .a import f\n")
    (pkg / "a.py").write_text("def f():\n    from .sub.b import g\n    return g\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "b.py").write_text("from .. import a\ng = 1\n")
    (pkg / "c.py").write_text("from . import a\n")  # an arrow into the cycle is not part of it
    assert cycles(import_graph({"pkg": pkg})) == [["pkg.a", "pkg.sub.b"]]
    (pkg / "sub" / "b.py").write_text("g = 1\n")
    assert cycles(import_graph({"pkg": pkg})) == []


def test_modules_are_at_most_600_lines():
    over = [f"{_shown(p)} ({n} lines)" for p, _ in modules(PACKAGES).values()
            if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES]
    assert not over, over


def test_functions_are_at_most_80_code_lines_or_say_why():
    over = long_functions(PACKAGES)
    assert not over, over


def test_the_length_check_counts_code_not_docstrings(tmp_path):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    body = "".join(f"    x{i} = {i}\n" for i in range(MAX_FUNCTION_CODE_LINES - 1))  # with the def: 80
    doc = '    """' + "\n" * 50 + '    """\n'
    (pkg / "__init__.py").write_text(f"def ok():\n{doc}{body}\n\ndef over():\n{body}    return 1\n\n"
                                     f"{LONG_MARKER} one kernel\ndef excused():\n{body}    return 1\n")
    found = long_functions({"pkg": pkg})
    assert len(found) == 1 and "over (81 code lines)" in found[0], found


def report(most: int = 12) -> str:
    """The longest functions (code lines), the longest modules (lines) and the import cycles, as text."""
    rows = []
    for mod, (path, _) in modules(PACKAGES).items():
        lines = path.read_text().splitlines()
        for node in ast.walk(ast.parse("\n".join(lines), str(path))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                rows.append((code_lines(node, lines), f"{_shown(path)}:{node.lineno} {node.name}"))
    sizes = sorted(((len(p.read_text().splitlines()), _shown(p)) for p, _ in modules(PACKAGES).values()), reverse=True)
    out = ["longest functions (code lines):"] + [f"  {n:5d}  {name}" for n, name in sorted(rows, reverse=True)[:most]]
    out += ["longest modules (lines):"] + [f"  {n:5d}  {name}" for n, name in sizes[:most]]
    out += [f"import cycles: {cycles(import_graph(PACKAGES)) or 'none'}"]
    return "\n".join(out)


if __name__ == "__main__":  # python tests/test_architecture.py: the figures these tests check
    print(report())


def test_no_merge_conflict_markers_left_in_tracked_text():
    """A merge left ``<<<<<<<``/``>>>>>>>`` lines in docs/design.md once; git lists the tracked files."""
    import subprocess
    files = subprocess.run(["git", "ls-files", "*.py", "*.md", "*.toml", "*.txt", "*.sh", "*.cfg"], cwd=ROOT,
                           capture_output=True, text=True).stdout.split()
    if not files:
        pytest.skip("not a git checkout")
    marked = []
    for name in files:
        path = ROOT / name
        if not path.is_file():
            continue
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            if line.startswith(("<<<<<<< ", ">>>>>>> ")) or line == "=======" and name.endswith(".py"):
                marked.append(f"{name}:{n}")
    assert not marked, f"merge conflict markers: {marked}"
