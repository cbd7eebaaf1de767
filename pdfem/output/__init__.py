"""Results files: the HDF5 writer (with its XDMF for ParaView) and the reader."""
