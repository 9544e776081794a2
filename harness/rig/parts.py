"""What a virtual rig is built from, and the snapshot it gives of itself."""

from __future__ import annotations

from dataclasses import dataclass

from harness.model.bearing import BearingConfig
from harness.model.building import BuildingConfig
from harness.rig.config import RigConfig
from harness.rig.truth import resolve_truth


@dataclass(frozen=True)
class RigParts:
    """What the rig is built from: the rig's true building and bearing, its rig section and tolerance."""

    building: BuildingConfig
    bearing: BearingConfig
    rig: RigConfig
    rtol: float = 1e-6

    @classmethod
    def from_profile(cls, profile) -> RigParts:
        """From a :class:`~harness.profile.Profile` (its ``rig`` section, or the defaults).

        The building and bearing are the rig's truth: the profile's ``structure`` and
        ``bearing`` with ``rig.truth`` over them (:mod:`harness.rig.truth`).
        """
        rig = getattr(profile, "rig", None) or RigConfig()
        truth = resolve_truth(profile.structure, profile.bearing, rig.truth)
        return cls(truth.building, truth.bearing, rig, profile.simulation.rtol)


@dataclass(frozen=True)
class RigState:
    """A snapshot of the rig for tests and consoles.

    Attributes
    ----------
    drive_state, fault_code : int
        As in ACTUATOR_STATUS (see :mod:`harness.rig.drive`).
    pressure_ok : bool
    actuator_force_N, command_N : float
        Actuator force now and the latest commanded force (N).
    rig_time_s, record_time_s : float
        Rig time (sub-steps taken, s) and time into the record (s).
    step_index : int
        Lockstep steps since entering lockstep or the last reset.
    table_running, lockstep : bool
    active_faults : tuple of int
        Fault ids (:mod:`harness.rig.faults`) active now.
    frames_received : int
        Frames the rig took off the bus.
    """

    drive_state: int
    fault_code: int
    pressure_ok: bool
    actuator_force_N: float
    command_N: float
    rig_time_s: float
    record_time_s: float
    step_index: int
    table_running: bool
    lockstep: bool
    active_faults: tuple[int, ...]
    frames_received: int
