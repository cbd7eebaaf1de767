"""Rigid-body motion: prescribed rigid bodies, the free-floating 6-DOF ship and its
hydrostatics, moving frames that carry elastic structures, and the shaft loads of rotating ones.

Everything here moves as a rigid body or rides on one; the finite elements it carries come
from :mod:`pdfem.fem`. Every kind implements :class:`pdfem.fem.base.Structure`.
"""
