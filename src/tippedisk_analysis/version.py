"""The package version (read by pyproject.toml and stored in every dataset)."""

__version__ = "0.5.0"
