"""The live console of a run: the loop's status drawn in a terminal by a process of its own.

- :mod:`.live`: :class:`~harness.console.live.LiveConsole`, the loop's side: starts the child
  process, and draws the last frame itself when there is no terminal to hand over.
- :mod:`.view`: the child process (``python -m harness.console.view``), which attaches to the
  loop's status block (:mod:`harness.loop.status`) and redraws it.

The package imports nothing at import: the child process starts with rich, numpy and the
status block only.
"""
