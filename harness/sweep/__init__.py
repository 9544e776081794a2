"""Studies at scale: ``harness sweep`` runs one offline simulation per case of a study file.

A study file (:mod:`.study`) names a base profile and its axes: records, PGA levels,
controllers, ``--set``-style parameter axes and Monte-Carlo distributions
(:mod:`.distributions`). :mod:`.cases` expands it into cases, each keyed by a hash of its
resolved inputs; :mod:`.resolve` turns a case into its profile, validated like the file;
:mod:`.worker` runs a case exactly as ``harness simulate`` does (the simulation itself is
handed in by the command, so this package imports nothing from the runs above it);
:mod:`.engines` spreads cases over local worker processes or a Dask cluster;
:mod:`.store` writes one row per case as it goes (Parquet, or CSV without pyarrow) and
tells which cases are done, so a rerun resumes; :mod:`.driver` ties these together.
:mod:`.summary`, :mod:`.curves`, :mod:`.plots` and :mod:`.report` turn the rows into
tables, IDA and fragility curves.
"""
