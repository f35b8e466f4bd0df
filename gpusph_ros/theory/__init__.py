"""Analytic solutions the solver is checked against: what theory says a flow does."""
