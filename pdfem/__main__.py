"""``python -m pdfem`` runs the command line."""

import sys

from pdfem.cli.main import main

sys.exit(main())
