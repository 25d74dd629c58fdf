"""The ``weather-mi`` command line: argument parsing and the commands (``commands``) and what ``info``
prints (``summary``)."""
from .commands import main

__all__ = ["main"]
