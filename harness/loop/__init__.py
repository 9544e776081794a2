"""The soft-real-time control loop: the tick, its runner and timing statistics (the scheduler and
the host's real-time set-up are in :mod:`harness.realtime`)."""
