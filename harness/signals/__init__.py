"""The signals of a run: its per-sample columns and the peak responses computed from them.

- :mod:`.columns`: every column's name, unit and place, defined once (``signals.csv``, the
  control row, the simulated and the twin's columns).
- :mod:`.peaks`: the peak responses people compare (SPEC 5), from a case's columns or a run folder.

The package imports nothing at import, so the model, the loop and the recorder can each take
the column names without pulling in the others.
"""
