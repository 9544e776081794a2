"""Replay of a run from its own log: its ticks again, through the same tick code, tick for tick.

:mod:`harness.replay.canlog` reads the run's ``can.log``; :mod:`harness.replay.recorded` what a run
folder keeps for replay (and refuses a folder recorded without it); :mod:`harness.replay.feed`
hands each tick the frames it consumed and the figures the loop gave it;
:mod:`harness.replay.engine` runs the loop on them; :mod:`harness.replay.compare` compares the
frames it sends with the run's, bit for bit (exact replay), or its commands with the run's
(what-if replay, open loop).
"""
