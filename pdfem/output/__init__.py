"""Results files: the HDF5 writer (with its XDMF for ParaView) and the reader."""

from pdfem.output.results import ResultsWriter, read_results

__all__ = ["ResultsWriter", "read_results"]
