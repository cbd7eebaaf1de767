"""Geometry shared by the ice and the structures: shapes, the particle lattice, cell hashing."""
