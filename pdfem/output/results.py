"""Compatibility: the old home of the results writer and reader, re-exporting their names.

The results file code now lives in one module per concept: :mod:`pdfem.output.writer`
(:class:`ResultsWriter`), :mod:`pdfem.output.reader` (:func:`read_results`),
:mod:`pdfem.output.ranks` (:func:`rank_file`), :mod:`pdfem.output.xdmf`,
:mod:`pdfem.output.frames`, :mod:`pdfem.output.histories` and :mod:`pdfem.output.layout`.
Import from ``pdfem.output`` (or those modules); this module only keeps
``pdfem.output.results`` imports working while pdfem/run is being restructured, and is to be
deleted once nothing imports it.
"""

from pdfem.output.frames import VIEW_BATCH
from pdfem.output.histories import HISTORY_BLOCK
from pdfem.output.layout import CELL_FIELDS, REQUIRED_ICE_FIELDS, REQUIRED_STRUCTURE_FIELDS
from pdfem.output.ranks import rank_file
from pdfem.output.reader import read_results
from pdfem.output.writer import ResultsWriter
from pdfem.output.xdmf import XDMF_TOPOLOGY

__all__ = ["CELL_FIELDS", "HISTORY_BLOCK", "REQUIRED_ICE_FIELDS", "REQUIRED_STRUCTURE_FIELDS",
           "VIEW_BATCH", "XDMF_TOPOLOGY", "ResultsWriter", "rank_file", "read_results"]
