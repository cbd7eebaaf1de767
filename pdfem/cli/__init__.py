"""The ``pdfem`` command line: :mod:`pdfem.cli.main` parses the arguments and runs a command."""
