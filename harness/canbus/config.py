"""The ``can:`` section of a profile: interface, channel, bitrate, protocol version and message rates.

Defaults fit 500 Hz control on a 1 Mbit/s bus with about 30 % load (see
:mod:`drivers.protocol.busload`). ``fd: true`` selects the CAN FD variant of the protocol
(``drivers/protocol/rig_fd.dbc``): every frame an FD frame with bit-rate switching, the whole sensor set in
one SENSOR_SET frame. Every periodic message of ``drivers/protocol/rig.dbc`` takes its rate from one
field here (:data:`RATE_FIELDS`); event messages (E-stop, rig
control, drive reset) are budgeted at the rate they may burst at.

The section is the harness's (built and checked by :mod:`harness.config.schema`); the
drivers never see it. :mod:`harness.canbus.link` hands its values to the drivers as
plain arguments (interface, channel, bitrate, rates as a mapping, ...).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from drivers.protocol.protocol_values import CURRENT_PROTOCOL_VERSION, SENSOR_SET_PARTS
from harness.config.input_limits import DEFAULT_RATE_HZ
from harness.config.schema import internal, quantity

#: DBC message name -> the CanConfig field holding its rate (Hz).
RATE_FIELDS: dict[str, str] = {
    "ESTOP": "estop_rate_hz",
    "ACTUATOR_CMD": "command_rate_hz",
    "TABLE_SENSORS": "sensor_frame_rate_hz",
    "BASE_SENSORS": "sensor_frame_rate_hz",
    "ACTUATOR_STATUS": "status_rate_hz",
    "HEARTBEAT": "heartbeat_rate_hz",
    "STORY_DRIFTS": "story_sensor_rate_hz",
    "FLOOR_ACCELS": "story_sensor_rate_hz",
    "RIG_CONTROL": "rig_control_rate_hz",
    "RIG_STATUS": "rig_status_rate_hz",
    "DRIVE_RESET": "rig_control_rate_hz",  # one frame before arming; budgeted as the other harness event message
}

#: The CAN FD protocol (``can.fd: true``, ``drivers/protocol/rig_fd.dbc``): SENSOR_SET carries the whole sensor
#: set at the sensor rate, in place of the four classic sensor messages (``SENSOR_SET_PARTS``), which
#: are then not sent (0 Hz).
FD_RATE_FIELDS: dict[str, str] = {"SENSOR_SET": "sensor_frame_rate_hz"}

#: Further senders of a message, each at its own rate (Hz): the ESTOP ID carries the harness's
#: (or any node's) active stop at ``estop_rate_hz`` and the panel's heartbeat at ``estop_panel_rate_hz``.
EXTRA_RATE_FIELDS: dict[str, tuple[str, ...]] = {"ESTOP": ("estop_panel_rate_hz",)}


@dataclass(frozen=True)
class CanConfig:
    """CAN bus and protocol settings (profile section ``can``).

    Attributes
    ----------
    interface : str
        Any python-can interface name: ``virtual``, ``socketcan``, ``pcan``, ``kvaser``, ...
    channel : str
        Interface channel: ``vcan0``/``can0`` for socketcan, a shared name for virtual.
    bitrate_bps : int
        Nominal bitrate (bit/s): the whole classic frame, the arbitration phase of an FD frame.
        socketcan takes it from ``ip link``; it still sets the bus-load budget.
    fd : bool
        Use the CAN FD variant of the protocol (``drivers/protocol/rig_fd.dbc``). False, the default, keeps
        classic CAN, which every CAN controller speaks; a bus with a classic-only node must stay classic.
    data_bitrate_bps : int
        Data-phase bitrate of FD frames (bit/s; ignored for classic CAN). 5 Mbit/s by default:
        the highest data rate ISO 11898-2:2016 specifies transceiver timing for, so common CAN FD
        transceivers and adapters run it; the data phase of a 32-byte sensor set (358 bits worst
        case) then takes 72 us, and 2 kHz control loads the bus 33.5 % (worst case,
        :mod:`drivers.protocol.busload`), inside the default ``max_bus_load`` of 50 % with room for error
        frames and retransmissions. 2 Mbit/s would load it 60.7 % at 2 kHz (refused; 32.4 % at
        1 kHz), 4 Mbit/s 38.1 %. The data phase has no arbitration, so the cable's round trip does
        not bound it as it bounds the nominal rate; a short, terminated lab bus (the harness's
        adapter, the rig's sensor concentrator and the servo controller, a few metres) carries it
        with the controllers' transmitter delay compensation on. Lower it for a longer bus or
        long stubs, and the loop rate with it.
    max_bus_load : float
        Largest allowed share of the bitrate (0..1) the configured messages may need.
    protocol_version : int
        The DBC ``ProtocolVersion`` this profile was written for; a different DBC is refused.
    sensor_rate_hz : float or None
        Rate of the base-mat and table sensor frames (Hz); None (the default): once per tick of the
        loop, so ``--rate`` moves them with it. A rig whose sensor concentrator sends at a rate of its
        own sets it (the loop-rate check refuses one too slow for the loop).
    story_sensor_rate_hz ... rig_control_rate_hz : float
        Rates of the other messages (Hz); see :data:`RATE_FIELDS`.
    loop_rate_hz : float
        The loop's tick rate (Hz), ``control.rate_hz``: not a key of the section. The profile fills it
        in (:class:`harness.profile.Profile`), so the one rate the profile sets is the actuator
        command's rate (:attr:`command_rate_hz`) and, by default, the sensors'.
    timestamp_source : {"poll", "message"}
        Receive time of a sample: the ``now`` passed to ``poll`` (default; same clock
        as the loop), or the frame's own ``msg.timestamp`` (wall-clock epoch seconds for
        socketcan, virtual and seqpacket), which the reader moves onto the loop's clock
        (``now - (time.time() - msg.timestamp)`` as the frame is handled), so ages are right
        in both modes; a timestamp from the future is invalid and trips ``sensor_stale``.
    max_frames_per_poll : int
        Upper bound of frames one ``poll`` handles, so a flooded bus cannot stall a tick.
    dbc_path : str
        DBC file; empty means the packaged ``drivers/protocol/rig.dbc``.
    peer_group : str
        ``seqpacket`` interface only: a group whose members may join the channel besides this
        user (checked on every connection with the peer's kernel credentials; docs/SAFETY.md,
        "Threat model"). Empty, the default: this user alone.
    """

    interface: str = quantity("virtual", doc="python-can interface (virtual, socketcan, pcan, kvaser, ...)")
    channel: str = quantity("harness", doc="interface channel, e.g. vcan0, can0, PCAN_USBBUS1")
    bitrate_bps: int = quantity(1_000_000, gt=0, le=1_000_000, doc="CAN bitrate (classic CAN; the nominal rate of CAN FD)")
    fd: bool = quantity(False, doc="CAN FD variant of the protocol (drivers/protocol/rig_fd.dbc): true or false")
    data_bitrate_bps: int = quantity(5_000_000, gt=0, le=8_000_000, doc="CAN FD data-phase bitrate (bit/s)")
    max_bus_load: float = quantity(0.5, gt=0.0, le=1.0, doc="largest allowed share of the bitrate")
    protocol_version: int = quantity(CURRENT_PROTOCOL_VERSION, ge=0, doc="ProtocolVersion the profile expects of the DBC")
    sensor_rate_hz: float | None = quantity(
        None, unit="Hz", gt=0.0, le=10_000.0,
        doc="TABLE_SENSORS and BASE_SENSORS (FD: SENSOR_SET) rate; none (default): once per tick, control.rate_hz",
    )
    story_sensor_rate_hz: float = quantity(250.0, unit="Hz", gt=0.0, le=10_000.0, doc="STORY_DRIFTS and FLOOR_ACCELS rate")
    status_rate_hz: float = quantity(250.0, unit="Hz", gt=0.0, le=10_000.0, doc="ACTUATOR_STATUS rate")
    heartbeat_rate_hz: float = quantity(100.0, unit="Hz", gt=0.0, le=10_000.0, doc="HEARTBEAT rate")
    estop_rate_hz: float = quantity(100.0, unit="Hz", gt=0.0, le=10_000.0, doc="ESTOP repetition rate while active (budgeted)")
    estop_panel_rate_hz: float = quantity(
        20.0, unit="Hz", gt=0.0, le=1_000.0, doc="E-stop panel heartbeat (ESTOP, source 3, active=0) rate (budgeted)",
    )
    rig_status_rate_hz: float = quantity(50.0, unit="Hz", gt=0.0, le=10_000.0, doc="RIG_STATUS rate (virtual rig)")
    rig_control_rate_hz: float = quantity(
        10.0, unit="Hz", gt=0.0, le=10_000.0, doc="RIG_CONTROL and DRIVE_RESET burst rate (budgeted)",
    )
    timestamp_source: Literal["poll", "message"] = quantity("poll", doc="receive time: poll's now, or msg.timestamp")
    max_frames_per_poll: int = quantity(256, gt=0, doc="frames one poll handles at most")
    dbc_path: str = quantity("", doc="DBC file; empty = packaged drivers/protocol/rig.dbc")
    peer_group: str = quantity("", doc="seqpacket: a group whose members may join besides this user; empty = this user only")
    loop_rate_hz: float = internal(
        DEFAULT_RATE_HZ, doc="the loop's tick rate, control.rate_hz: filled in by the profile, never set in one",
    )

    def __post_init__(self) -> None:
        if not self.interface.strip():
            raise ValueError("interface is empty; expected a python-can interface name such as 'virtual' or 'socketcan'")
        if not self.channel.strip():
            raise ValueError("channel is empty; expected a channel such as 'vcan0'")
        if self.fd and self.data_bitrate_bps < self.bitrate_bps:
            raise ValueError(
                f"data_bitrate_bps ({self.data_bitrate_bps}) is below bitrate_bps ({self.bitrate_bps}); "
                "expected a CAN FD data rate at least the nominal rate"
            )

    @property
    def command_rate_hz(self) -> float:
        """ACTUATOR_CMD's rate (Hz): once per tick of the loop, :attr:`loop_rate_hz`."""
        return self.loop_rate_hz

    @property
    def sensor_frame_rate_hz(self) -> float:
        """The base-mat and table sensors' rate (Hz): :attr:`sensor_rate_hz`, or once per tick when it is none."""
        return self.loop_rate_hz if self.sensor_rate_hz is None else self.sensor_rate_hz

    def rates_hz(self) -> dict[str, float]:
        """Message name -> configured rate (Hz), for every message in :data:`RATE_FIELDS`.

        A message with several senders (:data:`EXTRA_RATE_FIELDS`) gets the sum of their rates.
        With :attr:`fd`, SENSOR_SET takes the sensor rate and the messages it replaces 0 Hz.
        """
        rates = {name: float(getattr(self, field)) for name, field in RATE_FIELDS.items()}
        if self.fd:
            rates.update({name: float(getattr(self, field)) for name, field in FD_RATE_FIELDS.items()})
            rates.update(dict.fromkeys(SENSOR_SET_PARTS, 0.0))
        for name, fields in EXTRA_RATE_FIELDS.items():
            rates[name] += sum(float(getattr(self, field)) for field in fields)
        return rates
