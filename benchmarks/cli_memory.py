"""Peak memory (bytes per grid cell) and wall time of the command line on large WRF domains: the real WRF
supercell (``../shared/data/wrf/wrfout_quarter_ss_0130.nc``, 100 x 100 x 50) tiled into larger domains,
each command run as a child process and measured by ``os.wait4`` (its peak resident set size, ru_maxrss).

    .venv/bin/python benchmarks/cli_memory.py [--sizes 400 800] [--commands info render] [--rounds 1]
    .venv/bin/python benchmarks/cli_memory.py --repo /work/main --repo .    # before (main) vs after (this tree)
    .venv/bin/python benchmarks/cli_memory.py --sizes 800 --commands info render satellite view
    .venv/bin/python benchmarks/cli_memory.py --sizes 1800x1000 --commands satellite --resolution 3

A size is ``N`` (N x N) or ``NXxNY`` (west-east x south-north), multiples of 100.

``view`` is what ``weather-mi view FILE`` does before it serves the page: the input read, the optics and the
slicer warmed up for the first view (``viewer.serve.prepare(warm=True)``), then the process ends.

The tiled wrfout files are written once to ``--tmp`` (default /tmp/weather-mi-tiles; never into the
repository): only the variables the reader uses, the supercell repeated n/100 times along x and y (seams
and all). With several ``--repo`` trees the commands run tree after tree, round after round, in one run,
and the table gives each tree's time and peak against the first tree's (ratios: the machine is shared).
"bytes/cell" is the peak RSS over the cells of the domain's Hydrometeors grid (51 x n x n after the
vertical regridding), the interpreter and its libraries included (about 0.4-0.5 GB).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve()
WRF = HERE.parents[2] / "shared" / "data" / "wrf" / "wrfout_quarter_ss_0130.nc"
KEEP = ("Times", "QCLOUD", "QRAIN", "QICE", "QSNOW", "QGRAUP", "QVAPOR", "P", "PB", "T", "PH", "PHB", "ALT",
        "HGT", "MU", "MUB", "XLAT", "XLONG", "ZNU", "ZNW", "DNW", "P_TOP")
NZ = 51  # levels of the supercell's regridded grid (its native 50 layers at their mean depth, 402 m)
COMMANDS = {
    "info": ["info", "{file}"],
    "render": ["render", "{file}", "--spp", "8", "--size", "64x48", "--camera", "orbit", "--sky", "constant",
               "-o", "{out}/render.exr"],
    "render_noair": ["render", "{file}", "--spp", "8", "--size", "64x48", "--camera", "orbit", "--sky", "constant",
                     "--atmosphere", "none", "-o", "{out}/render.exr"],  # render without its default air
    "satellite": ["satellite", "{file}", "--lat", "35", "--lon", "-97", "--date", "2024-05-20T21:00:00Z",
                  "--resolution", "{resolution}", "--spp", "4", "-o", "{out}/sat.nc"],
}
CHILD = ("import sys, runpy; sys.path.insert(0, sys.argv.pop(1)); import weather_mi; "
         "print('weather_mi from', weather_mi.__file__, file=sys.stderr); "
         "from weather_mi.cli.commands import main; sys.exit(main(sys.argv[1:]))")
# ``view``: what ``weather-mi view FILE`` does before it serves (the input read, the optics, the slicer warmed up
# for the first view at its default 320 x 240), then exit instead of serving
COMMANDS["view"] = ["--view", "{file}"]
CHILD_VIEW = ("import sys; sys.path.insert(0, sys.argv.pop(1)); import weather_mi; "
              "print('weather_mi from', weather_mi.__file__, file=sys.stderr); "
              "from weather_mi.cli.commands import release_freed_memory; release_freed_memory(); "
              "from weather_mi.viewer.recipe import VolumeRecipe; from weather_mi.viewer.serve import prepare; "
              "prepare(VolumeRecipe(path=sys.argv[2]), None, size=(320, 240), warm=True)")


def tiled_wrfout(n, folder: Path, ny: int | None = None) -> Path:
    """The supercell tiled into an n x ny domain (west-east x south-north; multiples of 100; ny defaults to n),
    written once to ``folder``."""
    import netCDF4
    ny = n if ny is None else ny
    path = folder / (f"wrfout_supercell_{n}x{ny}.nc")
    if path.is_file():
        return path
    folder.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".part")
    with netCDF4.Dataset(WRF) as src, netCDF4.Dataset(tmp, "w", format="NETCDF4") as dst:
        rx = n // src.dimensions["west_east"].size
        ry = ny // src.dimensions["south_north"].size
        sizes = {"west_east": n, "south_north": ny, "west_east_stag": n + 1, "south_north_stag": ny + 1}
        for name, dim in src.dimensions.items():
            dst.createDimension(name, None if dim.isunlimited() else sizes.get(name, len(dim)))
        attrs = {k: src.getncattr(k) for k in src.ncattrs()}
        attrs.update({"WEST-EAST_GRID_DIMENSION": n + 1, "SOUTH-NORTH_GRID_DIMENSION": ny + 1})
        dst.setncatts(attrs)
        for name in KEEP:
            if name not in src.variables:
                continue
            var = src.variables[name]
            out = dst.createVariable(name, var.dtype, var.dimensions)
            out.setncatts({k: var.getncattr(k) for k in var.ncattrs()})
            data = var[:]
            if var.dimensions[-2:] == ("south_north", "west_east"):
                data = np.tile(data, (1,) * (data.ndim - 2) + (ry, rx))
            out[:] = data
    tmp.rename(path)
    return path


def size_of(text: str) -> tuple[int, int]:
    """(nx, ny) of a ``--sizes`` entry: "800" or "1800x1000"."""
    nx, _, ny = text.partition("x")
    return int(nx), int(ny or nx)


def run(repo: Path, argv: list[str], log: Path) -> tuple[float, int, int]:
    """(wall time s, peak RSS bytes, exit status) of ``weather-mi argv`` run with the code of ``repo``."""
    t0 = time.perf_counter()
    with open(log, "w") as out:
        child = CHILD_VIEW if argv[:1] == ["--view"] else CHILD
        proc = subprocess.Popen([sys.executable, "-c", child, str(repo), *argv], stdout=out, stderr=subprocess.STDOUT,
                                cwd=str(repo))
        _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    return time.perf_counter() - t0, usage.ru_maxrss * 1024, proc.returncode


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=size_of, nargs="+", default=[(400, 400), (800, 800)],
                    help="domain sizes: N or NXxNY (multiples of 100)")
    ap.add_argument("--resolution", type=float, default=4.0, help="satellite pixel size in km (default 4)")
    ap.add_argument("--commands", nargs="+", default=["info", "render"], choices=sorted(COMMANDS))
    ap.add_argument("--repo", type=Path, action="append", help="a tree whose weather_mi to run (repeatable; "
                    "default this one)")
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--tmp", type=Path, default=Path("/tmp/weather-mi-tiles"))
    a = ap.parse_args(argv)
    if not WRF.is_file():
        print(f"{WRF} is absent: nothing to measure")
        return 0
    repos = [r.resolve() for r in (a.repo or [HERE.parents[1]])]
    rows = []
    for nx, ny in a.sizes:
        n = f"{nx}x{ny}"
        path = tiled_wrfout(nx, a.tmp, ny)
        for cmd in a.commands:
            results = {r: [] for r in repos}
            for rnd in range(a.rounds):
                for i, repo in enumerate(repos):
                    out = a.tmp / f"out-{i}"
                    out.mkdir(exist_ok=True)
                    args = [s.format(file=path, out=out, resolution=f"{a.resolution:g}") for s in COMMANDS[cmd]]
                    log = a.tmp / f"{cmd}-{n}-{i}.log"
                    t, rss, rc = run(repo, args, log)
                    print(f"  {n}x{NZ} {cmd:9s} {repo}: {t:7.1f} s {rss / 2 ** 30:6.2f} GiB rc {rc} ({log})",
                          flush=True)
                    results[repo].append((t, rss, rc))
            rows.append((n, cmd, results))
    cells = {f"{nx}x{ny}": NZ * nx * ny for nx, ny in a.sizes}
    print(f"\n{'domain':<14}{'command':<11}{'tree':<28}{'time (s)':>10}{'peak (GiB)':>12}{'bytes/cell':>12}"
          f"{'time ratio':>12}{'mem ratio':>11}")
    for n, cmd, results in rows:
        base = None
        for repo, res in results.items():
            t = min(r[0] for r in res)
            rss = max(r[1] for r in res)
            ok = all(r[2] == 0 for r in res)
            base = base or (t, rss)
            print(f"{f'{n}x{NZ}':<14}{cmd:<11}{str(repo)[-27:]:<28}{t:>10.1f}{rss / 2 ** 30:>12.2f}"
                  f"{rss / cells[n]:>12.0f}{t / base[0]:>12.2f}{rss / base[1]:>11.2f}{'' if ok else '  FAILED'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
