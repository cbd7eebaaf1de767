"""pdfem's model library: parametric gmsh model scripts and the case files that use them.

Installed as the package ``pdfem.models``; ``pdfem mesh NAME`` finds a model here by name.
"""
