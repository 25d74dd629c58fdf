"""``weather-mi view``: check the input and the port, build the storm, then serve the viewer with Panel
(Bokeh's Tornado server) on 127.0.0.1, websocket origins checked, warming the slicer up (kernels, the
first view's rays) in the background while the browser loads the page.

Everything that can be wrong with the input is found before anything is served (exit code 2 from the
CLI). Each browser tab gets its own ViewerSession; closing the tab stops its render thread and its
reference process.
"""
from __future__ import annotations

import socket
import sys
import time

from .recipe import VolumeRecipe

LOCAL_HOSTS = ("127.0.0.1", "localhost", "::1")


def host_warning(host: str) -> str | None:
    """What to say when the viewer binds an address other machines can reach."""
    if host in LOCAL_HOSTS:
        return None
    return (f"weather-mi view: warning: serving on {host}, reachable from other machines; the viewer has no "
            "authentication (anyone who can reach the port can use it, and start renders)")


def check_port(host: str, port: int) -> int:
    """The port to serve on (``port``, or a free one for 0); a clear error if it is taken."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        try:
            s.bind((host, int(port)))
        except OSError as exc:
            raise RuntimeError(f"cannot serve on {host}:{port}: {exc.strerror or exc} (is another viewer running? "
                               "choose another --port, or --port 0 for a free one)") from exc
        return s.getsockname()[1]


def initial_time(storm, time_option) -> int:
    """The index of ``--time`` (an index or a timestamp, ``weather_mi.io.times``) among the storm's times;
    default the last."""
    if time_option is None:
        return storm.first_time
    from ..io.times import parse_time, select_times
    return select_times(list(storm.times), parse_time(time_option), "--time")[0]


def prepare(recipe: VolumeRecipe, time_option=None, progress=print, size: tuple[int, int] = (320, 240),
            warm: bool = True, air: dict | None = None):
    """The Storm (input read and checked, optics of the starting time) and the first ViewState (``air``: its
    ``atmosphere``, ``aod``, ``ozone``, ``water_vapour``; default none). With
    ``warm``, the slicer is warmed up for that view (kernels compiled, rays cached) before returning;
    ``serve`` warms it in the background instead, while the browser loads the page."""
    from .frames import Storm
    from .state import ViewCamera, ViewState
    from .session import default_distance_km
    t0 = time.perf_counter()
    storm = Storm(recipe)
    state = ViewState(time=initial_time(storm, time_option), camera=ViewCamera(distance_km=default_distance_km(storm)),
                      width=int(size[0]), height=int(size[1]), **(air or {}))
    if warm:
        storm.warm_up(state)
    progress(f"weather-mi view: {recipe.label}, {len(storm.times)} time(s), read in {time.perf_counter() - t0:.1f} s")
    return storm, state


def serve(recipe: VolumeRecipe, *, host: str = "127.0.0.1", port: int = 5006, open_browser: bool = True,
          time_option=None, reference_kw: dict | None = None, size: tuple[int, int] = (320, 240),
          air: dict | None = None) -> None:
    """Serve the viewer until Ctrl-C (blocking); ``air``: the starting view's atmosphere (``prepare``)."""
    import panel as pn
    from .session import ViewerSession
    warning = host_warning(host)
    if warning:
        print(warning, file=sys.stderr)
    port = check_port(host, port)  # before the slow part: a taken port is said at once
    storm, state = prepare(recipe, time_option, size=size, warm=False, air=air)
    port = check_port(host, port)
    origins = [f"{h}:{port}" for h in ("127.0.0.1", "localhost")] + ([f"{host}:{port}"] if host not in LOCAL_HOSTS else [])
    server = pn.serve({"/": lambda: ViewerSession(storm, state, reference_kw).layout}, port=port, address=host,
                      websocket_origin=origins, show=False, start=False, title="weather-mi", threaded=False,
                      # a closed tab's session (its render thread, its reference process) ends within seconds
                      check_unused_sessions_milliseconds=1000, unused_session_lifetime_milliseconds=1000)
    server.start()
    import threading
    threading.Thread(target=storm.warm_up, args=(state,), daemon=True, name="weather-mi warm-up").start()
    url = f"http://{'localhost' if host in LOCAL_HOSTS else host}:{port}/"
    print(f"weather-mi view: serving {url} (Ctrl-C to stop)", flush=True)
    if open_browser:
        import webbrowser
        webbrowser.open(url)
    try:
        server.io_loop.start()
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
