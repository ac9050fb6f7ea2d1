"""The jobs users run: deviation and its statistics, streaming, Dask, batches, clearance."""
