"""After a run: summary tables, CSV, plots and spectra of a results file."""
