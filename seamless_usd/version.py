"""The package's version, in a module of its own so that any step can record it without importing the API."""

__all__ = ["__version__"]

__version__ = "0.1.0"
