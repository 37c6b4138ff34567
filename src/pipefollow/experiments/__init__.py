"""Experiments: configuration, the trial unit of work, runner, results store, figures and report."""
