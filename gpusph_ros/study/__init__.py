"""Convergence studies: study files, cases run on Dask, the results table and its charts."""
