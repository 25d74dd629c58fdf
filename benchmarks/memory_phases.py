"""Where a command's peak memory comes from: one ``weather-mi`` command run in this process while a thread
samples the resident set size every 10 ms, with the peak RSS inside each phase (opening the file, the optics,
the Mitsuba medium, the majorant grids, the render) and the RSS held when it ends, in bytes per grid cell.

    .venv/bin/python benchmarks/memory_phases.py render /tmp/weather-mi-tiles/wrfout_supercell_400x400.nc \
        --spp 8 --size 64x48 --camera orbit --sky constant -o /tmp/mp/render.exr

(the tiled files are ``benchmarks/cli_memory.py``'s). The phases nest (the medium is built inside the render):
a phase's peak includes what its callers hold.
"""
from __future__ import annotations

import importlib
import sys
import threading
import time

PHASES = (("weather_mi.cli.options", "open_source", "open"),
          ("weather_mi.optics.volume", "optical_volume", "optics"),
          ("weather_mi.kernel.scene_dict", "medium_dict", "medium"),
          ("weather_mi.display.aerial", "eye_air", "eye air"),
          ("weather_mi.kernel.plugins.medium_setup", "GridCache.texel", "majorants"),
          ("weather_mi.reference.render", "_cloud_pixels", "cloud pixels"),
          ("weather_mi.reference.checkpoints", "fingerprint", "fingerprint"),
          ("mitsuba", "load_dict", "load_dict"),
          ("weather_mi.reference.render", "render_reference", "render"),
          ("weather_mi.satellite.imagery", "satellite_scene", "satellite scene"),
          ("weather_mi.satellite.imagery", "render_satellite", "satellite render"))


def rss_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096


class Sampler(threading.Thread):
    def __init__(self):
        super().__init__(daemon=True)
        self.peak, self.running = rss_bytes(), True

    def run(self):
        while self.running:
            self.peak = max(self.peak, rss_bytes())
            time.sleep(0.01)


def wrap(sampler, rows, module, qualname, label):
    mod = importlib.import_module(module)
    owner, name = (getattr(mod, qualname.split(".")[0]), qualname.split(".")[1]) if "." in qualname else (mod, qualname)
    fn = getattr(owner, name)

    def wrapped(*a, **k):
        outer = sampler.peak
        sampler.peak = start = rss_bytes()
        t0 = time.perf_counter()
        try:
            return fn(*a, **k)
        finally:
            peak = max(sampler.peak, rss_bytes())
            rows.append((label, time.perf_counter() - t0, start, peak, rss_bytes()))
            sampler.peak = max(outer, peak)
    setattr(owner, name, wrapped)


def main() -> int:
    import weather_mi.cli.commands as commands
    sampler, rows = Sampler(), []
    sampler.start()
    for module, qualname, label in PHASES:
        wrap(sampler, rows, module, qualname, label)
    shape = {}
    import weather_mi.optics.volume as volume
    inner = volume.optical_volume

    def optics(hyd, *a, **k):
        shape["cells"] = int(hyd["rho_air"].size)
        return inner(hyd, *a, **k)
    volume.optical_volume = optics
    import weather_mi.cli.options as options
    opened = options.open_source

    def open_source(*a, **k):  # ``info`` builds no volume: the cells of what was read
        out = opened(*a, **k)
        hyd = out[0] if isinstance(out, tuple) else out
        if hasattr(hyd, "data_vars") and "rho_air" in hyd:
            shape.setdefault("cells", int(hyd["rho_air"].size))
        return out
    options.open_source = open_source
    rc = commands.main(sys.argv[1:])
    sampler.running = False
    cells = shape.get("cells", 1)
    print(f"\n{'phase (as they end)':<20}{'time (s)':>10}{'peak (GiB)':>12}{'B/cell: at start':>18}{'peak':>8}{'at end':>8}")
    for label, t, start, peak, end in rows:
        print(f"{label:<20}{t:>10.2f}{peak / 2 ** 30:>12.2f}{start / cells:>18.0f}{peak / cells:>8.0f}{end / cells:>8.0f}")
    print(f"process peak {max(sampler.peak, 0) / 2 ** 30:.2f} GiB, {sampler.peak / cells:.0f} B/cell over {cells} cells")
    return rc


if __name__ == "__main__":
    sys.exit(main())
