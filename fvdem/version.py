"""fvdem's version (a leaf: what made a run names it, and the package metadata reads it)."""
__version__ = "0.3.0"
