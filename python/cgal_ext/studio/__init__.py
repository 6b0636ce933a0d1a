"""The editing studio: a page in the browser over a local aiohttp server (python3 -m cgal_ext.studio SCAN)."""
from .session import Session, StudioError

__all__ = ["Session", "StudioError"]
