"""Distributed-memory parallelism: static domain partitions of the ice and their halos."""
