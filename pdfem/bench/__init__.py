"""Performance measurements behind ``pdfem bench`` (figures, not tests)."""
