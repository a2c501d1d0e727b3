"""The MIMU4444BT binary stream (docs/formats.md): 8 IMUs per packet, checksummed, read vectorised.

Packet (106 bytes): 0xAA; a 3-byte packet counter; a big-endian uint32 time stamp; for each of the
8 IMUs six big-endian int16 (accelerometer x, y, z, gyro x, y, z, counts); a big-endian uint16
checksum = the sum of all preceding bytes mod 2^16. A packet that fails its checksum is dropped and
reading resynchronises on the next 0xAA. IMUs 2, 4, 6, 8 sit on the bottom of the board: their axes
map into the array frame by C_BOTTOM.
"""
import numpy as np

from ..errors import DataError, opt

IMUS = 8
PACKET = 1 + 3 + 4 + IMUS * 12 + 2
RATE_HZ = 62.5                      # the board's sample rate (the stream's README); sets the tick rate
COUNTS_PER_G = 2048                 # +-16 g range
G_DATASHEET = 9.80665               # m/s^2 per g of the counts (the stream's README)
C_BOTTOM = np.array([[0, -1, 0], [-1, 0, 0], [0, 0, -1]])


def looks_like(head):
    """True when the first bytes of a file hold two consecutive packets that pass their checksum."""
    b = np.frombuffer(head, dtype=np.uint8).astype(np.int64)
    for s in np.flatnonzero(b[: max(len(b) - 2 * PACKET + 1, 0)] == 0xAA):
        if all(b[p: p + PACKET - 2].sum() % 65536 == b[p + PACKET - 2] * 256 + b[p + PACKET - 1]
               for p in (s, s + PACKET)):
            return True
    return False


#: Bytes read at a time: memory is bounded by this and by the bytes kept per packet (10), never by the
#: file; a file with no valid packet in its first chunk is refused there.
CHUNK = 1 << 22


def _valid(b):
    """Starts of the packets in byte array b that pass their checksum (overlapping candidates included)."""
    starts = np.flatnonzero(b[: max(len(b) - PACKET + 1, 0)] == 0xAA)
    c = np.concatenate([[0], np.cumsum(b, dtype=np.int64)])          # byte sums without a copy per packet
    stated = b[starts + PACKET - 2].astype(np.int64) * 256 + b[starts + PACKET - 1]
    return starts[(c[starts + PACKET - 2] - c[starts]) % 65536 == stated]


def packets(path, imu):
    """The time stamp bytes (P, 4) and IMU `imu`'s accelerometer bytes (P, 6: three big-endian int16) of
    the packets that pass their checksum, in stream order, and the number of bytes outside them (a cut first
    packet, packets that failed their checksum). Read CHUNK bytes at a time."""
    off = 8 + (imu - 1) * 12
    stamps, imus, kept, end, size = [], [], 0, 0, 0      # end: the first byte a next packet may start at
    try:
        with open(path, "rb") as fh:
            carry, base = np.zeros(0, np.uint8), 0         # carry: the tail a packet may straddle
            while True:
                chunk = np.frombuffer(fh.read(CHUNK), dtype=np.uint8)
                size += len(chunk)
                b = np.concatenate([carry, chunk]) if len(carry) else chunk
                last = not len(chunk)
                pick = []
                for s in _valid(b).tolist():   # resynchronise: a valid packet never overlaps the previous one
                    if base + s >= end:
                        pick.append(s)
                        end = base + s + PACKET
                if pick:
                    at = np.array(pick)[:, None]
                    stamps.append(b[at + np.arange(4, 8)])
                    imus.append(b[at + np.arange(off, off + 6)])
                    kept += len(pick)
                if not kept and size >= CHUNK:
                    raise DataError(f"{path}: no packet with a valid checksum in its first {CHUNK >> 20} MiB; "
                                    "not a MIMU4444BT stream", param="log")
                if last:
                    break
                keep = min(PACKET - 1, len(b))
                carry, base = b[len(b) - keep:].copy(), base + len(b) - keep
    except OSError as e:
        raise DataError(f"{path}: cannot read ({e.strerror})", param="log") from None
    if size < PACKET:
        raise DataError(f"{path}: {size} bytes, shorter than one {PACKET}-byte MIMU packet", param="log")
    if not kept:
        raise DataError(f"{path}: no packet with a valid checksum; not a MIMU4444BT stream", param="log")
    return np.concatenate(stamps), np.concatenate(imus), size - kept * PACKET


#: Time stamps that may repeat, go back or jump before a stream is refused: a few resets (the packet count then
#: gives the time), never a share of the stream.
MAX_JUMPS, JUMP_SHARE = 10, 0.001


def read(path, imu):
    """Time (s, from the unwrapped time stamps) and the accelerometer of IMU `imu` (1-8) in the array
    frame, m/s^2 (COUNTS_PER_G counts per G_DATASHEET); the quantisation step (one count, m/s^2); the
    number of bytes skipped (outside packets that pass their checksum); and the number of time stamps
    that repeat, go back or jump by over 100 steps (a reset): when there are any, time is taken from the
    packet count at the median step, and the caller says so."""
    if not 1 <= imu <= IMUS:
        raise DataError(f"{opt('imu')} {imu}: the MIMU4444BT stream holds IMUs 1 to {IMUS}")
    stamp, own, skipped = packets(path, imu)
    ts = stamp.astype(np.int64) @ np.array([1 << 24, 1 << 16, 1 << 8, 1])
    ticks = np.diff(ts) % (1 << 32)                                  # the 32-bit stamp wraps
    forward = (ticks > 0) & (ticks < 1 << 31)                        # back: over half the range modulo 2^32
    if not forward.any():
        raise DataError(f"{path}: the time stamps do not advance", param="log")
    step = float(np.median(ticks[forward]))
    jumps = int(np.count_nonzero(~forward | (ticks > 100 * step)))
    if jumps > max(MAX_JUMPS, JUMP_SHARE * len(ticks)):       # a reset or two is said; a clock at random is no clock
        raise DataError(f"{path}: {jumps} of {len(ticks)} time stamps repeat, go back or jump: these are no MIMU "
                        "stream's time stamps (or a damaged stream); record again", param="log")
    if jumps:
        t = np.arange(len(ts)) / RATE_HZ
    else:
        t = np.concatenate([[0.0], np.cumsum(ticks)]) / (step * RATE_HZ)
    raw = own.astype(np.int64)
    counts = raw[:, 0::2] * 256 + raw[:, 1::2]
    counts = np.where(counts >= 32768, counts - 65536, counts)       # big-endian int16
    if imu % 2 == 0:
        counts = counts @ C_BOTTOM.T
    unit = G_DATASHEET / COUNTS_PER_G
    return t, counts * unit, unit, skipped, jumps
