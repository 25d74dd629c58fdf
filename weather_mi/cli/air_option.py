"""``--atmosphere clear`` in ``render``: the air inside the model's box (part of the path tracer's medium,
``optics.air.inside``) and along the eye rays outside it (``display.aerial``; ``--sky air``: the air's own
sky in place of a sky model: its diffuse light into the box, ``kernel.air_sky``, and its single-scattering sky
along the eye rays)."""
from __future__ import annotations


ON_BY_DEFAULT = "air_on_by_default"  # a command's parser default: the atmosphere is on unless --atmosphere none


def add_options(p) -> None:
    """``--sky``, ``--atmosphere``, ``--aod``, ``--ozone`` (the scene options of the light and the air)."""
    p.add_argument("--sky", default="sunsky", choices=("sunsky", "constant", "none", "air"),
                   help="sunsky: Hosek-Wilkie (the default without the atmosphere; with --atmosphere clear the "
                        "air in the box counts part of the sky model's air twice); air: the clear atmosphere's "
                        "own sky: its diffuse light (all orders, DISORT) into the box as an envmap the camera does "
                        "not see, the box's own air in the path tracer, single scattering along the eye rays "
                        "outside it, the ground beyond the box dimmed by that air (render's default with "
                        "--atmosphere clear)")
    p.add_argument("--atmosphere", default="none", choices=("none", "clear"),
                   help="clear: a clear 1-D atmosphere (molecules, ozone, aerosol) on the sun's path, inside the "
                        "model's box (render: part of the medium) and along the eye rays outside it (render; animate "
                        "--renderer slices: the sun's colour per height, the sky scaled, the eye rays' air); "
                        "none: the sun as given, vacuum between the hydrometeors. Default: clear in render "
                        "(none with --integrator volpath or --legacy, whose sun it cannot colour, and with --tile-size), none elsewhere")
    add_aod_ozone(p)


def add_aod_ozone(p) -> None:
    """``--aod``, ``--ozone`` and ``--water-vapour``: the clear atmosphere's aerosol, ozone and water (render,
    animate, satellite)."""
    p.add_argument("--aod", type=float, default=None,
                   help="with --atmosphere clear: aerosol optical depth at 550 nm, in [0, 3] (default 0.1)")
    p.add_argument("--ozone", type=float, default=None,
                   help="with --atmosphere clear: ozone column in atm-cm, in [0, 0.6] (default 0.3)")
    p.add_argument("--water-vapour", type=float, default=None,
                   help="with --atmosphere clear: precipitable water in cm, in [0, 10] (default 1.4): its bands near "
                        "593 and 720 nm on the sun's path (the sun's colour; none at 450/550/650 nm)")


def on_by_default(p) -> None:
    """The command of parser ``p`` (render) has the atmosphere on by default, and with it ``--sky air``
    (:func:`resolve` fills them in)."""
    p.set_defaults(atmosphere=None, sky=None, **{ON_BY_DEFAULT: True})


def resolve(args) -> None:
    """``--atmosphere`` and ``--sky`` where the command left them to the defaults (None): "clear" and "air" where
    the atmosphere is on by default (except with ``--integrator volpath`` or ``--legacy``, whose sun is one of
    the scene's emitters, and a tiled render, ``--tile-size``: there "none"), else "none" and "sunsky"."""
    from ..scene.spec import default_sky
    on = getattr(args, ON_BY_DEFAULT, False)
    if args.atmosphere is None:
        own_sun = getattr(args, "integrator", "majorant") != "volpath" and not getattr(args, "legacy", False)
        tiled = getattr(args, "tile_size", None) is not None  # render --tile-size has no atmosphere yet
        args.atmosphere = "clear" if on and own_sun and not tiled else "none"
    if args.sky is None:
        args.sky = default_sky(args.atmosphere) if on else "sunsky"
    elif on and args.atmosphere == "clear" and args.sky == "sunsky":
        import sys
        print("note: --sky sunsky with --atmosphere clear counts the air in the box twice (Hosek-Wilkie's sky holds "
              "it already, and the box's air scatters light into the eye rays and the cloud again); --sky air "
              "(the default) does not", file=sys.stderr)


def in_box(vol, spec):
    """``vol`` with the air of ``spec.atmosphere`` inside its box (``optics.air.inside.scene_air``, as
    ``render_reference`` puts it there: molecules from the model's ``rho_air`` per level, which ``optical_volume``
    keeps); ``vol`` itself without an atmosphere."""
    from ..optics.air.inside import scene_air
    return scene_air(vol, spec.atmosphere)


VIEW_DEFAULT = "clear"  # ``view --atmosphere``'s default, as ``render``'s: every drag target holds with the air
# (benchmarks/slicing_air.py, benchmarks/README.md "the air's cost per drag frame"; benchmarks/viewer.py)


def add_view_options(p) -> None:
    """``view``'s ``--atmosphere``, ``--aod``, ``--ozone``: the starting view's air (a control of the page
    switches it), for the slicer's frames and the reference the page renders."""
    p.add_argument("--atmosphere", default=VIEW_DEFAULT, choices=("none", "clear"),
                   help="clear: a clear 1-D atmosphere on the sun's path (its colour by height) and along the eye rays "
                        f"inside the model's box and out, in the slicer and in the reference; default {VIEW_DEFAULT}")
    p.add_argument("--aod", type=float, default=0.1, help="aerosol optical depth at 550 nm, in [0, 3] (default 0.1)")
    p.add_argument("--ozone", type=float, default=0.3, help="ozone column in atm-cm, in [0, 0.6] (default 0.3)")
    p.add_argument("--water-vapour", type=float, default=1.4,
                   help="precipitable water in cm, in [0, 10] (default 1.4)")


def view_air(args) -> dict:
    """The ``ViewState`` fields of ``view``'s air options, checked (a ValueError names --aod, --ozone or
    --water-vapour)."""
    from ..optics.air.atmosphere import AOD_RANGE, OZONE_RANGE_ATM_CM, Atmosphere
    try:
        Atmosphere(aod_550=args.aod, ozone_atm_cm=args.ozone, water_vapour_cm=args.water_vapour)
    except ValueError as exc:
        raise ValueError(f"--aod must be in {list(AOD_RANGE)}, --ozone in {list(OZONE_RANGE_ATM_CM)} atm-cm and "
                         f"--water-vapour in [0, 10] cm: {exc}") from None
    return {"atmosphere": args.atmosphere, "aod": float(args.aod), "ozone": float(args.ozone),
            "water_vapour": float(args.water_vapour)}


def eye_rays_air(spec, vol, args):
    """The air along the eye rays outside the box (``display.aerial.eye_air``, the storm's shadow on it read from
    ``vol``'s extinction), computed before the render releases ``vol``'s grids (``render_reference(
    release_volume=True)``), for :func:`on_eye_rays`; None without an atmosphere. ``--spectral``: its terms per
    wavelength, projected to the spectral output's linear sRGB (``display.aerial.SpectralChannels``)."""
    if spec.atmosphere is None:
        return None
    from ..display.aerial import eye_air
    return eye_air(spec, vol, sky_air=args.sky == "air", spectral=bool(getattr(args, "spectral", False)))


def on_eye_rays(img, spec, vol, args, air=None):
    """``img`` seen through the air outside the box (``display.aerial.with_eye_air``; ``air``: its
    :func:`eye_rays_air`, computed before ``vol``'s grids were released), with the air's sky for ``--sky air``;
    ``img`` itself without an atmosphere. A spectral render (``img.xyz``) takes the terms per wavelength
    (:func:`eye_rays_air` with ``--spectral``) and its X, Y, Z follow its R, G, B."""
    if spec.atmosphere is None:
        return img
    from ..display.aerial import with_eye_air
    return with_eye_air(img, spec, vol, sky_air=args.sky == "air", air=air)

