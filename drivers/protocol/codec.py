"""The CAN codec: ``drivers/protocol/rig.dbc`` (or its FD variant ``rig_fd.dbc``) compiled once into fast encoders and decoders.

cantools parses the DBC once (:func:`load_protocol`); every message is then compiled
into a :class:`MessageCodec` that packs and unpacks its signals with plain integer
arithmetic (the DBC's Intel layout, scale, offset, signedness and range), so a tick
never looks anything up by name, parses, or builds a dict. Test suites check these
codecs bit for bit against cantools' own ``Message.encode``/``decode``.

Values in this API are SI (m, m/s, m/s^2, N, s) in the DBC's signal order, without
the ``crc`` and ``counter`` signals, which the codec owns (:mod:`drivers.protocol.e2e`).

A DBC describes one frame format throughout: every message classic CAN (``rig.dbc``), or
every message a CAN FD frame (``rig_fd.dbc``: ``BA_ "VFrameFormat"`` ``StandardCAN_FD`` on each
message, which cantools reads as ``Message.is_fd``; ``BA_ "CANFD_BRS"`` whether its data phase
switches to the data bit rate). :func:`load_protocol` refuses a mixed file, and one whose
format is not the one the profile's ``can.fd`` asks for.

The receive-side checks and counts live in :mod:`drivers.protocol.decoder`.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import cantools
import numpy as np

from drivers.errors import ProtocolError
from drivers.protocol.e2e import parse_data_ids, profile2_crc, protect
from drivers.protocol.frame_kernel import signal_plan, unpack_signals
from drivers.protocol.protocol_values import VALUE_TABLES, choices_of

#: The packaged protocol description (classic CAN).
DEFAULT_DBC = Path(__file__).with_name("rig.dbc")
#: Its CAN FD variant: the same messages as FD frames, plus SENSOR_SET.
DEFAULT_FD_DBC = Path(__file__).with_name("rig_fd.dbc")
#: Data-field lengths a classic CAN frame can have (bytes).
CLASSIC_LENGTHS = frozenset(range(9))
#: Data-field lengths a CAN FD frame can have (bytes; ISO 11898-1:2015, DLC 9..15 code 12..64).
FD_LENGTHS = frozenset((*range(9), 12, 16, 20, 24, 32, 48, 64))
#: Signals every message carries and the codec fills in itself.
E2E_SIGNALS = ("crc", "counter")
_F32 = struct.Struct("<f")
_U32 = struct.Struct("<I")


@dataclass(frozen=True, slots=True)
class SignalLayout:
    """One signal compiled from the DBC (Intel byte order).

    ``raw_min``/``raw_max`` are the DBC's physical ``[min|max]`` converted to raw
    integers; a received raw value outside them is out of range.
    """

    name: str
    unit: str
    start: int
    length: int
    signed: bool
    is_float: bool
    scale: float
    offset: float
    minimum: float
    maximum: float
    raw_min: int
    raw_max: int

    @property
    def mask(self) -> int:
        """Bit mask of the raw field (``2**length - 1``)."""
        return (1 << self.length) - 1


def _compile_signal(signal: cantools.database.can.Signal, message: str) -> SignalLayout:
    if signal.byte_order != "little_endian":
        raise ProtocolError(f"{message}.{signal.name}: byte order {signal.byte_order} instead of little_endian")
    if signal.is_float and signal.length != 32:
        raise ProtocolError(f"{message}.{signal.name}: float of {signal.length} bits instead of 32")
    scale, offset = float(signal.scale), float(signal.offset)
    lo_field = -(1 << (signal.length - 1)) if signal.is_signed else 0
    hi_field = (1 << (signal.length - 1)) - 1 if signal.is_signed else (1 << signal.length) - 1
    minimum = float(signal.minimum) if signal.minimum is not None else lo_field * scale + offset
    maximum = float(signal.maximum) if signal.maximum is not None else hi_field * scale + offset
    if signal.is_float:
        raw_min, raw_max = lo_field, hi_field
    else:
        raw_min = max(lo_field, math.ceil((minimum - offset) / scale - 1e-6))
        raw_max = min(hi_field, math.floor((maximum - offset) / scale + 1e-6))
    return SignalLayout(
        signal.name, signal.unit or "", signal.start, signal.length, signal.is_signed, signal.is_float,
        scale, offset, minimum, maximum, raw_min, raw_max,
    )


class MessageCodec:
    """Packs and unpacks one message's payload signals (SI values, DBC order, no crc/counter).

    Attributes
    ----------
    name : str
        Message name in the DBC, e.g. ``"TABLE_SENSORS"``.
    frame_id : int
        11-bit arbitration ID.
    length : int
        DLC in bytes.
    data_ids : tuple of int
        The 16 E2E profile-2 Data-IDs.
    is_fd : bool
        Sent as a CAN FD frame (the DBC's ``VFrameFormat``).
    bitrate_switch : bool
        An FD frame whose data phase runs at the data bit rate (the DBC's ``CANFD_BRS``; False for classic).
    signals : tuple of SignalLayout
        The payload signals, in DBC order.
    signal_names : tuple of str
        Their names.
    """

    def __init__(self, message: cantools.database.can.Message, data_ids: tuple[int, ...], bitrate_switch: bool = False):
        names = [s.name for s in message.signals]
        for required, start, length in (("crc", 0, 8), ("counter", 8, 4)):
            sig = message.get_signal_by_name(required) if required in names else None
            if sig is None or sig.start != start or sig.length != length:
                raise ProtocolError(f"{message.name}: expected signal {required!r} at bit {start}, {length} bits")
        self.name: str = message.name
        self.frame_id: int = message.frame_id
        self.length: int = message.length
        self.data_ids = data_ids
        self.is_fd: bool = bool(message.is_fd)
        self.bitrate_switch: bool = self.is_fd and bool(bitrate_switch)
        lengths = FD_LENGTHS if self.is_fd else CLASSIC_LENGTHS
        if self.length not in lengths:
            kind = "a CAN FD" if self.is_fd else "a classic CAN"
            raise ProtocolError(f"{message.name}: {self.length} data bytes is not a length {kind} frame has; "
                                f"expected one of {', '.join(map(str, sorted(lengths)))}")
        self.signals = tuple(_compile_signal(s, message.name) for s in message.signals if s.name not in E2E_SIGNALS)
        self.signal_names = tuple(s.name for s in self.signals)
        self._index = {name: i for i, name in enumerate(self.signal_names)}
        if message.is_extended_frame:
            raise ProtocolError(f"{message.name}: extended (29-bit) ID instead of an 11-bit ID")
        # flat per-signal tuples, so the per-frame loops touch no attributes
        self._pack_plan = tuple(
            (
                s.minimum - (0.0 if s.is_float else 0.5 * s.scale), s.maximum + (0.0 if s.is_float else 0.5 * s.scale),
                s.offset, s.scale, s.raw_min, s.raw_max, s.mask, s.start, s.is_float,
            )
            for s in self.signals
        )
        #: The signals' plan for the compiled unpacking (:func:`drivers.protocol.frame_kernel.signal_plan`).
        self.plan = signal_plan(self.signals)
        self._float_bits = np.zeros(1, dtype=np.uint32)
        self._unpacked = np.zeros(len(self.signals))

    def index(self, signal: str) -> int:
        """Position of ``signal`` in this message's value sequences.

        Raises
        ------
        ProtocolError
            If the message has no such signal.
        """
        try:
            return self._index[signal]
        except KeyError as err:
            raise ProtocolError(f"{self.name} has no signal {signal!r}; expected one of: {', '.join(self.signal_names)}") from err

    def pack(self, data: bytearray | memoryview, values: Sequence[float]) -> None:
        """Pack SI ``values`` into ``data`` in place (crc and counter bits left zero).

        Raises
        ------
        ProtocolError
            Wrong number of values, or a value outside the DBC range (NaN included).
        """
        if len(values) != len(self.signals):
            raise ProtocolError(
                f"{self.name}: {len(values)} values instead of {len(self.signals)} ({', '.join(self.signal_names)})"
            )
        word = 0
        # no strict=: the lengths were checked just above, and zip with a keyword costs 0.3 us a frame
        for value, (lo, hi, offset, scale, raw_min, raw_max, mask, start, is_float) in zip(values, self._pack_plan):  # noqa: B905
            if not lo <= value <= hi:
                self._refuse(values)
            if is_float:
                raw = _U32.unpack(_F32.pack(value))[0]
            else:
                raw = round((value - offset) / scale)
                raw = raw_min if raw < raw_min else raw_max if raw > raw_max else raw
            word |= (raw & mask) << start
        data[0 : self.length] = word.to_bytes(self.length, "little")

    def _refuse(self, values: Sequence[float]) -> None:
        for sig, value, plan in zip(self.signals, values, self._pack_plan, strict=True):
            if not plan[0] <= value <= plan[1]:
                raise ProtocolError(
                    f"{self.name}.{sig.name}: {value!r} {sig.unit} is outside {sig.minimum:g}..{sig.maximum:g} {sig.unit}"
                )

    def encode_into(self, data: bytearray | memoryview, values: Sequence[float], counter: int) -> None:
        """Pack ``values``, then write ``counter`` and the CRC (a complete, protected frame)."""
        self.pack(data, values)
        protect(data, counter, self.data_ids)

    def encode(self, values: Sequence[float] | Mapping[str, float], counter: int) -> bytes:
        """Convenience (allocates): a protected payload from a sequence or a name -> value mapping."""
        if isinstance(values, Mapping):
            unknown = set(values) - set(self.signal_names)
            if unknown:
                raise ProtocolError(f"{self.name} has no signal {sorted(unknown)[0]!r}; expected: {', '.join(self.signal_names)}")
            missing = [name for name in self.signal_names if name not in values]
            if missing:
                raise ProtocolError(
                    f"{self.name}: no value for signal {missing[0]!r}; expected all of: {', '.join(self.signal_names)}"
                )
            values = [values[name] for name in self.signal_names]
        data = bytearray(self.length)
        self.encode_into(data, values, counter)
        return bytes(data)

    def unpack(self, data: bytes | bytearray | memoryview, out: list[float]) -> bool:
        """Unpack every payload signal of ``data`` into ``out`` (SI); False if one is out of range.

        ``data`` should have the message's length (missing bytes read as zeros). ``out`` is filled completely
        even when a value is out of range. The receive side's compiled unpacking
        (:func:`drivers.protocol.frame_kernel.unpack_signals`) does the work.
        """
        payload = np.frombuffer(data, dtype=np.uint8)
        if len(payload) < self.length:  # the missing bytes read as zeros (the kernel reads only within the length)
            payload = np.concatenate((payload, np.zeros(self.length - len(payload), dtype=np.uint8)))
        unpacked = self._unpacked
        ok = unpack_signals(payload, 0, self.plan, len(unpacked), unpacked, self._float_bits)
        out[: len(unpacked)] = unpacked.data
        return bool(ok)

    def crc_ok(self, data: bytes | bytearray) -> bool:
        """True when byte 0 holds the profile-2 CRC of the rest (``data`` of the right length)."""
        return data[0] == profile2_crc(data, self.length, self.data_ids)


class Protocol:
    """The compiled protocol: every message of the DBC by name and by ID.

    Build it with :func:`load_protocol`.

    Attributes
    ----------
    version : int
        The DBC's ``ProtocolVersion`` attribute.
    path : pathlib.Path
        The DBC it was loaded from.
    database : cantools.database.can.Database
        The parsed DBC (for tools and tests; the tick never touches it).
    messages : dict of str to MessageCodec
    by_id : dict of int to MessageCodec
    fd : bool
        Every message is a CAN FD frame (a DBC never mixes the two formats).
    """

    def __init__(self, database: cantools.database.can.Database, path: Path):
        self.database = database
        self.path = path
        attributes = database.dbc.attributes if database.dbc is not None else {}
        if "ProtocolVersion" not in attributes:
            raise ProtocolError(f"{path}: no ProtocolVersion attribute; expected BA_ \"ProtocolVersion\" <int>;")
        self.version = int(attributes["ProtocolVersion"].value)
        self.messages: dict[str, MessageCodec] = {}
        for message in database.messages:
            attrs = message.dbc.attributes if message.dbc is not None else {}
            if "E2EDataIDs" not in attrs or not attrs["E2EDataIDs"].value:
                raise ProtocolError(f"{path}: message {message.name} has no E2EDataIDs attribute; expected 16 Data-IDs")
            try:
                data_ids = parse_data_ids(str(attrs["E2EDataIDs"].value), message.name)
            except ValueError as err:
                raise ProtocolError(f"{path}: {err}") from err
            self.messages[message.name] = MessageCodec(message, data_ids, _bitrate_switch(database, message))
        self.by_id: dict[int, MessageCodec] = {m.frame_id: m for m in self.messages.values()}
        self.fd = self._frame_format()
        self._check_value_tables()

    def _frame_format(self) -> bool:
        """True when every message is an FD frame, False when none is; a mixed DBC is refused."""
        fd = [name for name, codec in self.messages.items() if codec.is_fd]
        if fd and len(fd) != len(self.messages):
            classic = next(name for name, codec in self.messages.items() if not codec.is_fd)
            raise ProtocolError(
                f"{self.path}: {fd[0]} is a CAN FD frame but {classic} a classic one; "
                "expected one frame format for every message (drivers/protocol/rig.dbc classic, drivers/protocol/rig_fd.dbc FD)"
            )
        return bool(fd)

    def value_table(self, message: str, signal: str) -> dict[int, str]:
        """The DBC's ``VAL_`` table of ``message.signal`` as ``{raw value: name}`` (empty if it has none).

        Raises
        ------
        ProtocolError
            If the message or signal does not exist.
        """
        self[message].index(signal)
        choices: Mapping[int, object] = self.database.get_message_by_name(message).get_signal_by_name(signal).choices or {}
        return {int(value): str(name) for value, name in choices.items()}

    def _check_value_tables(self) -> None:
        """Refuse a DBC whose value table of a named signal differs from the drivers' enum.

        A DBC without the message, the signal or a value table for it is accepted as before;
        one that names the values must name them as :data:`drivers.protocol.protocol_values.VALUE_TABLES` does.
        """
        for (message, signal), enum in VALUE_TABLES.items():
            codec = self.messages.get(message)
            if codec is None or signal not in codec.signal_names:
                continue
            found = self.value_table(message, signal)
            expected = choices_of(enum)
            if found and found != expected:
                raise ProtocolError(
                    f"{self.path}: VAL_ table of {message}.{signal} is {_describe(found)}; "
                    f"expected {_describe(expected)} (drivers.protocol.protocol_values.{enum.__name__})"
                )

    def choice(self, message: str, signal: str, label: str) -> int:
        """The raw value of a named choice from the DBC's ``VAL_`` table (look it up once).

        For example ``choice("ACTUATOR_STATUS", "drive_state", "ENABLED") == 2``.

        Raises
        ------
        ProtocolError
            If the message, signal or label does not exist.
        """
        choices = self.value_table(message, signal)
        for value, name in choices.items():
            if name == label:
                return value
        raise ProtocolError(
            f"{message}.{signal} has no choice {label!r}; expected one of: {', '.join(choices.values()) or 'none'}"
        )

    def __getitem__(self, name: str) -> MessageCodec:
        try:
            return self.messages[name]
        except KeyError as err:
            raise ProtocolError(f"no message {name!r} in {self.path.name}; expected one of: {', '.join(self.messages)}") from err


def _bitrate_switch(database: cantools.database.can.Database, message: cantools.database.can.Message) -> bool:
    """The message's ``CANFD_BRS`` attribute, or the DBC's default for it (no attribute: no switch)."""
    attrs = message.dbc.attributes if message.dbc is not None else {}
    if "CANFD_BRS" in attrs:
        return str(attrs["CANFD_BRS"].value) == "1"
    definitions = database.dbc.attribute_definitions if database.dbc is not None else {}
    definition = definitions.get("CANFD_BRS")
    return definition is not None and str(definition.default_value) == "1"


def _describe(choices: Mapping[int, str]) -> str:
    """``0 "OFF" 1 "READY" ...``, a value table as the DBC writes it."""
    return " ".join(f'{value} "{name}"' for value, name in sorted(choices.items()))


def load_protocol(path: str | Path | None = None, *, fd: bool | None = None) -> Protocol:
    """Parse a DBC with cantools and compile it (call once, at configure time).

    Parameters
    ----------
    path : str or Path, optional
        The DBC; default :data:`DEFAULT_DBC` (``drivers/protocol/rig.dbc``), or :data:`DEFAULT_FD_DBC`
        (``drivers/protocol/rig_fd.dbc``) when ``fd`` is True.
    fd : bool, optional
        The frame format the caller expects (the profile's ``can.fd``); None accepts either.

    Raises
    ------
    ProtocolError
        If the file is missing, does not parse, breaks the protocol's conventions (a value
        table that names a signal's values otherwise than :mod:`drivers.protocol.protocol_values` included,
        classic and FD messages mixed), or describes the other frame format than ``fd``.
    """
    dbc = Path(path) if path else DEFAULT_FD_DBC if fd else DEFAULT_DBC
    text = _read_dbc_text(dbc)
    try:
        database = cantools.database.load_string(text, database_format="dbc")
    except Exception as err:  # cantools raises several unrelated types for a bad file
        raise ProtocolError(f"{dbc}: not a readable DBC file: {_printable(str(err))}") from err
    assert isinstance(database, cantools.database.can.Database), "a DBC file loads as a CAN database"
    protocol = Protocol(database, dbc)
    if fd is not None and protocol.fd != fd:
        found, expected = ("CAN FD", "classic CAN") if protocol.fd else ("classic CAN", "CAN FD")
        raise ProtocolError(
            f"{dbc} describes {found} frames but can.fd is {'true' if fd else 'false'}, which expects {expected} "
            f"(the packaged {DEFAULT_FD_DBC.name if fd else DEFAULT_DBC.name}); set can.fd to match the DBC"
        )
    return protocol


#: Largest DBC file read (bytes); the rig's DBC is about 10 kB.
MAX_DBC_BYTES = 5_000_000
_CONTROL_BYTES = frozenset(range(0, 9)) | frozenset(range(14, 32)) | {127}


def _read_dbc_text(dbc: Path) -> str:
    """The DBC's text, refusing a missing file, a directory, a huge or a binary file with a short message."""
    if dbc.is_dir():
        raise ProtocolError(f"DBC file {dbc} is a directory, expected a DBC text file")
    try:
        size = dbc.stat().st_size
        if size > MAX_DBC_BYTES:
            raise ProtocolError(f"DBC file {dbc} is {size} bytes, expected a DBC text file under {MAX_DBC_BYTES} bytes")
        data = dbc.read_bytes()
    except FileNotFoundError as err:
        raise ProtocolError(f"DBC file {dbc} not found, expected an existing DBC file") from err
    except OSError as err:
        raise ProtocolError(f"cannot read DBC file {dbc}: {err.strerror or err}") from err
    bad = next((i for i, byte in enumerate(data) if byte in _CONTROL_BYTES), None)
    if bad is not None:
        raise ProtocolError(
            f"DBC file {dbc} is not a text file (control byte 0x{data[bad]:02x} at offset {bad}), expected a DBC text file"
        )
    try:
        return data.decode("cp1252")  # the encoding cantools reads DBC files in
    except UnicodeDecodeError as err:
        raise ProtocolError(f"DBC file {dbc}: byte 0x{data[err.start]:02x} at offset {err.start} is not cp1252 text, "
                            "expected a DBC text file") from err


def _printable(text: str, limit: int = 200) -> str:
    """``text`` cut to its first line and ``limit`` characters, with anything unprintable escaped."""
    line = text.strip().splitlines()[0] if text.strip() else ""
    shown = "".join(ch if ch.isprintable() else ascii(ch)[1:-1] for ch in line)
    return shown if len(shown) <= limit else shown[: limit - 3] + "..."


def check_protocol_version(protocol: Protocol, expected: int) -> None:
    """Refuse a DBC whose ``ProtocolVersion`` differs from the one the profile names.

    Raises
    ------
    ProtocolError
        Naming both versions.
    """
    if protocol.version != expected:
        raise ProtocolError(
            f"the profile names CAN protocol version {expected} but {protocol.path} is version {protocol.version}"
        )
