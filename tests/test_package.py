"""The package as a user meets it: what ``import weather_mi`` gives (every name the README uses), what it
does not do (select a Mitsuba variant, import the CLI), the plugins registered with every variant a
user selects, and the packaging metadata (dependency ranges, data files)."""
from __future__ import annotations

import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _run(script: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, cwd=ROOT)


def readme_names() -> list[str]:
    """Dotted names ``wm.a.b`` that the README's examples use."""
    text = (ROOT / "README.md").read_text()
    return sorted(set(re.findall(r"\bwm\.([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*)", text)))


def test_readme_finds_names():
    names = readme_names()
    assert "metrics.compare" in names and "synthetic.supercell" in names and "reference.cloud_mask" in names


def test_every_name_the_readme_uses_is_reachable_from_import_weather_mi():
    script = f"""
import weather_mi as wm
missing = []
for dotted in {readme_names()!r}:
    obj = wm
    for part in dotted.split("."):
        if not hasattr(obj, part):
            missing.append(dotted)
            break
        obj = getattr(obj, part)
print("missing:", missing)
"""
    out = _run(script)
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.strip() == "missing: []"


def test_import_selects_no_variant_and_imports_no_cli():
    out = _run("import sys, weather_mi, mitsuba as mi; print(mi.variant(), 'weather_mi.cli.commands' in sys.modules)")
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.split() == ["None", "False"]


def test_both_plugins_registered_with_every_variant_selected_after_import():
    """A dict scene can name ``majorant_volpath`` and ``hydrometeor_mixture`` in any variant chosen after
    ``import weather_mi``, without a render having run first."""
    script = """
import weather_mi, mitsuba as mi
for variant in ("scalar_rgb", "llvm_ad_rgb"):
    mi.set_variant(variant)
    for kind, d in (("phase", {"type": "hydrometeor_mixture"}), ("integrator", {"type": "majorant_volpath"})):
        try:
            mi.load_dict(d)
            print(variant, kind, "ok")
        except Exception as exc:
            print(variant, kind, "not registered" if "unknown" in str(exc).lower() or "not found" in str(exc).lower()
                  else "registered")
"""
    out = _run(script)
    assert out.returncode == 0, out.stderr[-3000:]
    assert "not registered" not in out.stdout, out.stdout
    assert len(re.findall(r"(?:scalar_rgb|llvm_ad_rgb) (?:phase|integrator) (?:ok|registered)", out.stdout)) == 4, out.stdout


def test_plugins_registered_with_a_variant_selected_before_import():
    script = """
import mitsuba as mi
mi.set_variant("llvm_ad_rgb")
import weather_mi
try:
    mi.load_dict({"type": "majorant_volpath"})
    print("ok")
except Exception as exc:
    print("unknown" if "unknown" in str(exc).lower() else "registered")
"""
    out = _run(script)
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.strip() in ("ok", "registered"), out.stdout


# ---------------------------------------------------------------- OpticalVolume: complete and read-only

def test_optical_volume_is_complete_and_read_only_once_built():
    import dataclasses

    import numpy as np

    import weather_mi as wm
    q = np.zeros((3, 4, 5))
    q[1, 2, 3] = 1e-3
    vol = wm.optical_volume(wm.from_arrays({"cloud": q, "ice": q}, 1.0, (100, 100, 100)), phase_quality="test")
    assert isinstance(vol.phase_tables, tuple) and len(vol.phase_tables) == len(vol.species)
    with pytest.raises(dataclasses.FrozenInstanceError):
        vol.phase_tables = vol.phase_tables[::-1]
    with pytest.raises(dataclasses.FrozenInstanceError):
        vol.bbox = ((0, 0, 0), (1, 1, 1))
    for name in ("beta_ext", "beta_total", "albedo", "weights"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(vol, name)[(0,) * getattr(vol, name).ndim] = 1.0
    # a changed copy is a new, equally complete volume; the arrays given to it stay the caller's
    albedo = np.full_like(vol.albedo, 0.5)
    v2 = dataclasses.replace(vol, albedo=albedo)
    assert v2.phase_tables == vol.phase_tables and albedo.flags.writeable
    with pytest.raises(wm.WeatherDataError, match="one table per species"):
        dataclasses.replace(vol, phase_tables=vol.phase_tables[:2])


def test_no_module_writes_the_volume_s_private_fields():
    offenders = [str(p.relative_to(ROOT)) for p in (ROOT / "weather_mi").rglob("*.py")
                 if re.search(r"\._phase_tables\b|\bvol\w*\.phase_tables\s*=[^=]", p.read_text())]
    assert offenders == []


# ---------------------------------------------------------------- packaging

def _pyproject() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def _name(requirement: str) -> str:
    return re.split(r"[<>=!~\[; ]", requirement, maxsplit=1)[0].lower()


def test_dependencies_are_ranges_and_the_exact_pins_live_in_constraints():
    project = _pyproject()["project"]
    requirements = project["dependencies"] + [r for extra in project["optional-dependencies"].values() for r in extra]
    assert not [r for r in requirements if "==" in r], "exact pins belong in constraints.txt"
    assert all(">=" in r for r in requirements), "every dependency has a tested lower bound"
    pins = {}
    for line in (ROOT / "constraints.txt").read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            name, version = line.split("==")
            pins[name.strip().lower()] = version.strip()
    assert sorted(pins) == sorted(_name(r) for r in requirements)
    for r in requirements:  # each pin inside its range's lower bound
        lower = re.search(r">=([\w.]+)", r).group(1)
        pin = pins[_name(r)]
        assert [int(x) for x in re.findall(r"\d+", pin)[:3]] >= [int(x) for x in re.findall(r"\d+", lower)[:3]], r
    setup = (ROOT / "setup.sh").read_text()
    assert "-c constraints.txt" in setup


def test_every_package_and_data_folder_is_declared():
    """setuptools warns about (and would drop) folders of the package that the configuration omits:
    weather_mi.optics.phase.data (the shipped phase tables) and weather_mi.study (``weather-mi validate``)."""
    tool = _pyproject()["tool"]["setuptools"]
    declared = set(tool["packages"])
    found = {".".join(p.relative_to(ROOT).parts) for p in (ROOT / "weather_mi").rglob("*")
             if p.is_dir() and p.name != "__pycache__" and any(f.is_file() for f in p.iterdir())}
    assert found | {"weather_mi"} == declared
    assert "package-dir" not in tool  # the plugins are inside the package (weather_mi/kernel/plugins)
    assert tool["package-data"]["weather_mi.optics.phase.data"] == ["*.npz"]


def test_every_public_name_is_reachable_and_the_short_names_are_their_modules():
    """``wm.__all__`` resolves in a fresh interpreter (the lazy subpackages and short names included), and each
    short name is the module it names: a module moved without its short name fails here."""
    out = _run("import weather_mi as wm\n"
               "missing = [n for n in wm.__all__ if not hasattr(wm, n)]\n"
               "wrong = [n for n, m in wm.SHORT_NAMES.items() if getattr(wm, n).__name__ != 'weather_mi.' + m]\n"
               "print(missing, wrong, sorted(wm.SUBPACKAGES))")
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.split("\n")[0] == ("[] [] ['cli', 'display', 'io', 'kernel', 'optics', 'plane_parallel', "
                                         "'reference', 'satellite', 'scene', 'slicing', 'study', 'viewer']")
