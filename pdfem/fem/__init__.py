"""Finite-element structures (scikit-fem): meshes, assembly, explicit time integration."""
