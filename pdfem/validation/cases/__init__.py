"""The validation cases, one module per case file (each exports ``CASES``, a tuple of
:class:`~pdfem.validation.case.ValidationCase`); :mod:`pdfem.validation.registry` lists them."""
