"""Experiments: many trials from one file, stored, summarized and reported.

The configuration's schema and its files, the trial (the unit of work), the runner, the results store, the run
folder, summaries, the paper's claims, the report, the readings study and figures.

May import every layer below but the command line.
"""
