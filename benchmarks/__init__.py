"""The performance suite behind ``pdfem bench`` (installed as ``pdfem.benchmarks``).

Figures, never tests: :mod:`.search` (neighbour search), :mod:`.step` (the OSB step, pair loop
vs full-family loop), :mod:`.mpi` (strong scaling of the distributed step) and
:mod:`.partition_model` (halo sizes and traffic of MPI partitions, no cluster needed). The
scripts beside them (``run.py``, ``paper_tables.py``, ``memory_10m.py``) are run from a
checkout; ``BENCHMARKS.md`` records what they measured.
"""
