"""What makes the loop real time on the host, apart from the loop itself.

- :mod:`.scheduler`: :class:`~harness.realtime.scheduler.FixedRateScheduler`, ticks against absolute deadlines.
- :mod:`.host`: the operating system's real-time treatment (SCHED_FIFO, CPU affinity, locked
  memory, the garbage collector), asked for and reported (profile section ``loop.realtime``).
- :mod:`.memory`: buffers whose pages are resident before the first tick writes them.
- :mod:`.interrupts`: Ctrl-C and SIGTERM: the operator's requests as flags, or a clean stop.

The package imports nothing at import: each module is imported on its own.
"""
