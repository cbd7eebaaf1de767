"""Results files: the HDF5 writer (with its XDMF for ParaView), the reader and per-rank files."""

from pdfem.output.ranks import rank_file
from pdfem.output.reader import read_results
from pdfem.output.writer import ResultsWriter

__all__ = ["ResultsWriter", "rank_file", "read_results"]
