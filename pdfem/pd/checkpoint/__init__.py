"""Checkpoint state of ice bodies: what a restart needs, per rank and by global numbers."""
