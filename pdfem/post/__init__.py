"""After a run: summary tables, CSV, plots and spectra of a results file.

One module per concept: :mod:`~pdfem.post.load` (open a results file, or say why not),
:mod:`~pdfem.post.summary` (the numbers), :mod:`~pdfem.post.table` (their text tables),
:mod:`~pdfem.post.csv` (the per-step histories as CSV), :mod:`~pdfem.post.spectrum`
(amplitude spectrum), :mod:`~pdfem.post.plots` (PNG plots) and :mod:`~pdfem.post.groups`
(which history is which).
"""

from pdfem.post.csv import LOAD_PREFIXES, UNITS, history_table, write_csv
from pdfem.post.load import load_results
from pdfem.post.plots import projection_axes, write_plots
from pdfem.post.spectrum import amplitude_spectrum
from pdfem.post.summary import summarize, time_average
from pdfem.post.table import format_summary

__all__ = ["LOAD_PREFIXES", "UNITS", "amplitude_spectrum", "format_summary", "history_table",
           "load_results", "projection_axes", "summarize", "time_average", "write_csv",
           "write_plots"]
