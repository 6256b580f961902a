"""Analytic models of vibratory transport and their cross-check against DEM."""
