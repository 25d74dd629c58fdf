"""The interactive browser viewer (issue 13): the slicer's frames streamed to a Panel app, with the
path-traced ground truth one click away. ``weather-mi view`` serves it; ``view(...)`` returns it for a
Jupyter notebook."""
