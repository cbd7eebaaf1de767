"""MPI: the communicator and the partition of ice bodies over ranks."""
