"""Running a case: build the bodies, advance them together, watch and checkpoint the run."""
