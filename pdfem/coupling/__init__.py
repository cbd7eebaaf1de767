"""Ice-structure coupling: surface-element contact, load transfer and subcycling."""
