"""The slicer's held-out tables with the air, from cached references only: today's views (front/side at 35 deg,
back at 20 deg, as ``study.runs.view``) with the clear atmosphere and the air's own sky (``study.runs.low_sun_view``),
and the 6 deg sun with the air and without it (issue 38 part 3, refit38). Issue 41's table (today's views
without the air) is ``calibrate_slicer.py --held-out-only``.

    python validation/slicer_air_tables.py --refs DIR [--data ../shared/data] [--size 64x48]
        [--fitted a.json,b.json] [--scenes wrf-supercell,wrf-plateau,bomex,rico] [--lightings front,side,back]

References are the RGB EXRs that ``validation/slicer_low_sun.py`` caches, read
from --refs by their names (``calibrate_slicer.cache_name``; of several plans the one of the lowest RSE);
nothing is rendered here: a missing reference is an error naming the file it looked for. The slicer's frames
are those of both scripts (128 slices, 2 x 2 points per pixel, slab jitter 1), with the shipped defaults and
the parameters of each --fitted file. CIEDE2000 / FLIP over the cloud pixels (``display.metrics.compare``).
"""
from __future__ import annotations

import argparse
import re
import sys
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from weather_mi.display import metrics  # noqa: E402
from weather_mi.io.image import Image  # noqa: E402
from weather_mi.optics.air import Atmosphere  # noqa: E402
from weather_mi.slicing import MODES, SliceParams, SliceRenderer  # noqa: E402
from weather_mi.study.runs import DATA_SCENES, StudyConfig, eye_transmittance, low_sun_view, view  # noqa: E402
from validation.calibrate_slicer import AIR_REFERENCES, LOW_SUN_DEG, read_fitted  # noqa: E402
from validation.slicer_low_sun import storm  # noqa: E402

DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
# (table, sun elevation or None for the view's own, atmosphere)
TABLES = (("today, air", None, True), ("6 deg, air", LOW_SUN_DEG, True), ("6 deg, no air", LOW_SUN_DEG, False))


def cached(refs: Path, tag: str, size: str, air: bool) -> Image:
    """The cached reference of ``tag`` (``calibrate_slicer.cache_name`` of any ``rse`` plan, seed 0): of several,
    the lowest RSE; SystemExit naming the pattern when there is none."""
    suffix = f"_{AIR_REFERENCES}_reference.exr" if air else "_reference.exr"
    pattern = re.compile(re.escape(f"{tag}_{size}_rse") + r"([0-9.e+-]+)" + re.escape(suffix) + "$")
    found = sorted((float(m.group(1)), p) for p in refs.iterdir() if (m := pattern.match(p.name)))
    if not found:
        raise SystemExit(f"slicer_air_tables: no reference {tag}_{size}_rse*{suffix} in {refs} "
                         "(render it with validation/slicer_low_sun.py)")
    return Image.load(found[0][1])


def rows_of(args, columns: dict) -> list:
    """One row per (storm, lighting, table): the view's CIEDE2000 / FLIP for each column's parameters."""
    width, height = (int(v) for v in args.size.split("x"))
    cfg = replace(StudyConfig(), width=width, height=height)
    rows = []
    for name in args.scenes.split(","):
        if not (Path(args.data) / DATA_SCENES[name][0]).is_file():
            raise SystemExit(f"slicer_air_tables: {Path(args.data) / DATA_SCENES[name][0]} absent (--data)")
        hyd, vol = storm(name, Path(args.data), cfg)
        slicer = SliceRenderer(vol, MODES["per-species/multiple"], slices=128)
        # the cloud mask: the camera (study.runs.view) is the same for every lighting, sun and air
        mask = metrics.cloud_mask(eye_transmittance(vol, view(vol, "front", cfg), 128))
        for lighting in args.lightings.split(","):
            for table, elevation, air in TABLES:
                el = view(vol, lighting, cfg).sun.elevation if elevation is None else elevation
                spec = low_sun_view(vol, lighting, cfg, el, Atmosphere() if air else None)
                tag = f"{name}_{lighting}_{el:g}deg_{'clear' if air else 'none'}"
                ref = cached(Path(args.refs), tag, args.size, air)
                row = {"table": table, "view": f"{name} {lighting} {el:g}",
                       "rse": (ref.metadata.get("noise") or {}).get("rse_mean", float("nan"))}
                for label, params in columns.items():
                    img = slicer.frame(spec, params, supersample=2)
                    m = metrics.compare(ref.radiance, img.radiance, mask=mask if mask.any() else "all")
                    row[label] = (m["ciede2000"], m["flip"])
                rows.append(row)
                print(row, flush=True)
    return rows


def print_tables(rows: list, labels: list) -> None:
    for table, *_ in TABLES:
        mine = [r for r in rows if r["table"] == table]
        if not mine:
            continue
        print(f"\n### {table} (CIEDE2000 / FLIP over cloud pixels)\n")
        print("| view | " + " | ".join(labels) + " | reference RSE |")
        print("|---|" + "---|" * len(labels) + "---|")
        for r in mine:
            print(f"| {r['view']} | " + " | ".join(f"{r[n][0]:.2f} / {r[n][1]:.3f}" for n in labels)
                  + f" | {r['rse']:.3f} |")
        print("| median | " + " | ".join(f"**{np.median([r[n][0] for r in mine]):.2f} / "
                                          f"{np.median([r[n][1] for r in mine]):.3f}**" for n in labels) + " | |")
        print("| mean CIEDE2000 | " + " | ".join(f"{np.mean([r[n][0] for r in mine]):.2f}" for n in labels) + " | |")
        print("| worst CIEDE2000 | " + " | ".join(f"{max(r[n][0] for r in mine):.2f}" for n in labels) + " | |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--refs", required=True, help="the folder of slicer_low_sun.py's cached references")
    ap.add_argument("--data", default=str(DEFAULT_DATA))
    ap.add_argument("--size", default="64x48")
    ap.add_argument("--fitted", default="", help="comma-separated fitted.json files: a column each")
    ap.add_argument("--scenes", default="wrf-supercell,wrf-plateau,bomex,rico")
    ap.add_argument("--lightings", default="front,side,back")
    args = ap.parse_args(argv)
    base = SliceParams(slab_jitter=1.0)
    columns = {"shipped defaults": base}
    for path in filter(None, args.fitted.split(",")):
        columns[Path(path).stem] = base.updated(**read_fitted(Path(path)))
    rows = rows_of(args, columns)
    print_tables(rows, list(columns))
    return 0


if __name__ == "__main__":
    sys.exit(main())
