"""Peridynamic ice: lattices, neighbour search, bond pairs and the LPS (ordinary state-based) kernels."""
