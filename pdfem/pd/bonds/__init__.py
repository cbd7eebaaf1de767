"""Bonds and the LPS law: neighbour search, bond weights, the pair and full-family loops.

Everything here works on flat arrays of one body's (or one rank's part of a body's) bonds:
the search that finds them (:mod:`~pdfem.pd.bonds.search`), their weights
(:mod:`~pdfem.pd.bonds.influence`, :mod:`~pdfem.pd.bonds.surface`), the LPS law per bond
(:mod:`~pdfem.pd.bonds.lps_law`) and the loops that apply it (the particle-pair loop,
:mod:`~pdfem.pd.bonds.pair_loop`, and the full-family reference loop,
:mod:`~pdfem.pd.bonds.family`). :mod:`~pdfem.pd.bonds.kernels` gathers their public functions.
"""
