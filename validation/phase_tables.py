"""Plots and a summary of the phase tables that ``weather_mi.optics.phase`` provides for the species presets.

    python validation/phase_tables.py [-o out/phase_tables] [--no-plates] [--plate-quality default]

Writes one PNG per table to the output folder: 4 pi p(theta) (1 = isotropic) on a log axis against
the scattering angle in degrees, one curve per RGB channel (650 / 550 / 450 nm in red / green /
blue), linear in angle on the left and logarithmic on the right (the forward diffraction peak); the
legend gives the asymmetry g and the cone fraction F(10 deg) (energy within 10 deg of forward) per
channel. Thin vertical lines mark the 22 and 46 deg halos for ice-class tables and the 138 deg
primary rainbow for rain. ``tables.md`` in the same folder lists g and F(5), F(10), F(20) deg per
table and channel, which preset / mode / species uses it, and a check of the two closed-form
tables (HG, Cornette-Shanks) against their exact g and cone fractions.

Tables: every table ``weather_mi.optics.phase.for_species`` builds for the "paper" and "physical" presets
in both modes ("per_species": Mie cloud, Mie rain at each preset's rain radius, ice columns,
snow, graupel; "paper": Mie cloud and ice columns), all shipped with the package at default quality
(no computation); plus ice plates (the other pristine habit; not used by a preset, not shipped:
computed at ``--plate-quality`` on the first run, ~1 min at "default", then cached on disk),
Cornette-Shanks g = 0.825 and Henyey-Greenstein g = 0.85.
"""
from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

CONES_DEG = (5.0, 10.0, 20.0)
CHANNELS = (("R", "650 nm", "tab:red"), ("G", "550 nm", "tab:green"), ("B", "450 nm", "tab:blue"))
HALOS_DEG = (22.0, 46.0)
RAINBOW_DEG = 138.0


def slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9.]+", "_", text).strip("_").lower()


def closed_forms():
    """(constructor, g, exact mean cosine, exact cone fraction F(g, theta0)) of the analytic tables."""
    from weather_mi.optics import phase
    return ((phase.cornette_shanks, 0.825, phase.cornette_shanks_mean_cosine, phase.cornette_shanks_cone_fraction),
            (phase.henyey_greenstein, 0.85, lambda g: g, phase.hg_cone_fraction))


def _kind(name: str, sp) -> str:
    """Which angles to mark: "rain" (bows), "ice" (halos) or "water"."""
    if name.startswith("mie_rain"):
        return "rain"
    return "ice" if sp.phase_class == "ice" else "water"


def collect(plates: bool, plate_quality: str):
    """[(key, title, table, kind, used_by)] in display order; kind in {"water", "rain", "ice", "analytic"}."""
    from weather_mi.optics import phase, species
    from weather_mi.optics.phase.species_tables import MODES, table_for

    found = {}  # table name -> [key, title, table, kind, used_by]
    for preset in species.PRESETS:
        for mode in MODES:
            for sp in species.preset(preset):
                t = table_for(sp, mode=mode, quality="default")
                if t.name not in found:
                    found[t.name] = [slug(t.name.split(":")[0]), t.name, t, _kind(t.name, sp), []]
                used = found[t.name][4]
                where = f"{preset}/{mode}"
                if used and used[-1][0] == where:
                    used[-1][1].append(sp.name)
                else:
                    used.append((where, [sp.name]))
    rows = [(k, ti, t, kind, [f"{w}: {', '.join(names)}" for w, names in used]) for k, ti, t, kind, used in found.values()]
    order = ["mie_cloud", "mie_rain", "ice_crystals", "snow", "graupel"]
    rows.sort(key=lambda r: next((i for i, k in enumerate(order) if r[0].startswith(k)), len(order)))
    if plates:
        t0 = time.perf_counter()
        t = phase.ice_crystals("plate", quality=plate_quality)
        dt = time.perf_counter() - t0
        if dt > 2:
            print(f"computed ice plates ({plate_quality} quality) in {dt:.0f} s; cached in {phase.cache_dir()}")
        at = next((i + 1 for i, r in enumerate(rows) if r[0].startswith("ice_crystals")), len(rows))
        rows.insert(at, (slug(t.name), f"{t.name} ({plate_quality} quality)", t, "ice",
                         ["no preset (pristine-habit alternative to columns)"]))
    for make, g, *_ in closed_forms():
        t = make(g)
        rows.append((slug(t.name), t.name, t, "analytic", ["closed form"]))
    return rows


def plot(path: Path, title: str, table, kind: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    deg = np.degrees(table.theta)
    y = 4 * np.pi * table.values
    g = table.g
    f10 = table.cone_fraction(np.radians(10.0))
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), gridspec_kw={"width_ratios": [3, 2]})
    positive = y[y > 0]
    ylim = (max(positive.min() * 0.5, 1e-4), positive.max() * 2)
    for ax, logx in zip(axes, (False, True)):
        m = deg > 0 if logx else slice(None)
        for c, (ch, wl, colour) in enumerate(CHANNELS):
            ax.plot(deg[m], y[m, c], color=colour, lw=0.9,
                    label=f"{ch} {wl}: g = {g[c]:.4f}, F(10\u00b0) = {f10[c]:.3f}")
        marks = HALOS_DEG if kind == "ice" else (RAINBOW_DEG,) if kind == "rain" else ()
        for a in marks:
            ax.axvline(a, color="0.35", lw=0.6, ls="--", zorder=0)
            if not logx:
                ax.text(a, 0.985, f" {a:g}\u00b0", fontsize=8, va="top", ha="left", color="0.3",
                        transform=ax.get_xaxis_transform())
        ax.set_yscale("log")
        ax.set_ylim(*ylim)
        ax.grid(True, which="major", lw=0.3, alpha=0.6)
        ax.set_ylabel("4\u03c0 p(\u03b8)   (1 = isotropic)")
        if logx:
            ax.set_xscale("log")
            ax.set_xlim(max(deg[deg > 0].min(), 1e-3), 180)
            ax.set_xlabel("scattering angle \u03b8 (deg, log scale)")
        else:
            ax.set_xlim(0, 180)
            ax.set_xticks(np.arange(0, 181, 20))
            ax.set_xlabel("scattering angle \u03b8 (deg)")
    axes[0].legend(fontsize=8, loc="upper right", bbox_to_anchor=(1.0, 0.93))
    fig.suptitle(f"{title}   [{table.theta.size} angles]", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def triple(values, fmt="{:.4f}") -> str:
    return " / ".join(fmt.format(v) for v in values)


def markdown(rows) -> str:
    lines = ["# Phase tables (weather_mi.optics.phase)", "",
             "Per channel R / G / B (650 / 550 / 450 nm). g = asymmetry parameter <cos theta>; "
             "F(x) = fraction of the scattered energy within x deg of forward.", "",
             "| table | angles | g | F(5\u00b0) | F(10\u00b0) | F(20\u00b0) | used by |",
             "|---|---|---|---|---|---|---|"]
    for key, title, t, kind, used in rows:
        f = [t.cone_fraction(np.radians(d)) for d in CONES_DEG]
        lines.append(f"| {title} (`{key}.png`) | {t.theta.size} | {triple(t.g)} | "
                     + " | ".join(triple(x, "{:.3f}") for x in f) + f" | {'; '.join(used)} |")
    lines += ["", "Closed-form check (green channel, table vs exact):", ""]
    analytic = [r for r in rows if r[3] == "analytic"]
    for (key, title, t, kind, used), (_, g, mean_cosine, cone) in zip(analytic, closed_forms()):
        gx, fx = mean_cosine(g), [cone(g, np.radians(d)) for d in CONES_DEG]
        ft = [t.cone_fraction(np.radians(d))[1] for d in CONES_DEG]
        lines.append(f"- {title}: g {t.g[1]:.6f} vs {gx:.6f}; "
                     + ", ".join(f"F({d:g}\u00b0) {a:.6f} vs {float(b):.6f}" for d, a, b in zip(CONES_DEG, ft, fx)))
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--out", default="out/phase_tables", help="output folder (default: out/phase_tables)")
    ap.add_argument("--no-plates", action="store_true", help="skip the ice-plate table (not shipped: computed once)")
    ap.add_argument("--plate-quality", default="default", choices=("test", "default", "high"))
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = collect(not args.no_plates, args.plate_quality)
    for key, title, table, kind, _ in rows:
        path = out / f"{key}.png"
        plot(path, title, table, kind)
        print(f"wrote {path}")
    md = markdown(rows)
    (out / "tables.md").write_text(md)
    print(f"wrote {out / 'tables.md'}\n")
    print(md)


if __name__ == "__main__":
    main()
