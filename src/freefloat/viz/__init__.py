"""Visualisation leaves: they read a plan and never feed back into planning.

Import :mod:`freefloat.viz.playback` (MeshCat) or :mod:`freefloat.viz.plots` (matplotlib)
directly; this package imports neither, so the core never loads a viewer.
"""

__all__: list[str] = []
