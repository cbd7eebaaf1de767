"""pdfem: ice loads on structures by peridynamics (ice) coupled with finite elements (structure).

All quantities are SI: metres, kilograms, seconds, newtons, pascals, joules.
"""

__version__ = "0.1.0"
