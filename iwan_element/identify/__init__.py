"""Identification: test records and units, loop and dissipation fits."""
