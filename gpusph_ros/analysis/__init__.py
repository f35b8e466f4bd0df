"""Analysis of recordings: read MCAP, the thesis's metrics, comparison with GPUSPH and experiment, charts."""
