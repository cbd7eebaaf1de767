"""The parallel layout of an ice body: which particles a rank holds, owns and exchanges.

A body held whole by one process and a body split over MPI ranks differ only in their layout
(:mod:`~pdfem.pd.layout.base`): the exchanges of halo values, the sums over owned particles
and the gathers to rank 0. This package also holds how a rank's part is built (the distributed
set-up), moved (migration, load balance) and how its stable step is found.
"""
