"""The soft-real-time control loop: scheduler, real-time setup, the tick, and timing statistics."""
