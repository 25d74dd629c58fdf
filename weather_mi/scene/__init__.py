"""The scene both renderers draw: SceneSpec with camera, sun, sky and ground (``spec``), the default framing
of a storm (``framing``), the sun's position from a time (``solar``) and where and when a dataset is
(``place``)."""
