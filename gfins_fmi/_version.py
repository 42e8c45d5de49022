"""The package's version, in one place (the package, the CLI and the dask workers' check
read it here)."""
__version__ = "0.1.0"
