"""Ice materials: the constitutive law of the bonds (the linear peridynamic solid today)."""
