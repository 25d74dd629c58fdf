"""Everything that touches Mitsuba 3 and Dr.Jit's core: the chosen variant (the only global state) and
plugin registration (``variant``), Dr.Jit settings (``jit_settings``), host arrays for kernels
(``jitarrays``), SceneSpec + OpticalVolume -> Mitsuba dicts (``scene_dict``, ``medium``) and the
plugins themselves (``plugins/``)."""
