"""Forces on ice particles other than their bonds (short-range contact between particles)."""
