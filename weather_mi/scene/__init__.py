"""The scene both renderers draw: SceneSpec with camera, sun, sky and ground (``spec``; the camera and a ray
table in ``camera``), the default framing of a storm (``framing``), the sun's position from a time (``solar``)
and where and when a dataset is (``place``), the ground under a domain with its own (``surface``: each column's,
with the sea's glint)."""
