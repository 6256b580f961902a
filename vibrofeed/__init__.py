"""vibrofeed: DEM simulation of vibratory bulk feeding of micro-parts."""

__version__ = "0.1.0"
