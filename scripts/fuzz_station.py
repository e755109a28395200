"""Real-process fuzz target: malformed vision and referee datagrams into a running station.

Usage: ``.venv/bin/python scripts/fuzz_station.py [--count 1000000] [--seed 1] [--rate 4000]``
(``make fuzz`` runs it after the property rounds, ``FUZZ_COUNT``; ``tests/fuzz/
test_station_fuzz.py`` runs it with ``--count 20000``).

It starts the whole station with ``python -m launcher --isolated`` (fieldsim keeps sending its
own good vision), then sends ``--count`` malformed datagrams on loopback multicast (TTL 0) to
the vision and referee groups and ports the launcher printed, paced at ``--rate`` datagrams/s
(default 4000: 10^6 in about 4 min).
The kinds are mixed deterministically from ``--seed`` (a pool of distinct datagrams is built
once, then drawn from): random bytes, truncated and byte-flipped valid packets, valid protobuf
with required fields missing, oversized (> the relay's 32 KiB, few), empty, strings that are
not UTF-8, enum values out of range, NaN/inf coordinates, huge repeated counts. Each datagram
in the pool is classified beforehand with the station's own parser
(``sslnet.streams.parse_message``) into the
reason the relay or the backend should count it under, or "accepted" (it parses: the world
model then drops frames whose capture time is random as "time out of range"; a consistent
fake clock would be learnt as a camera: that is spoofing, not a malformed datagram).

Every ``--check-every`` seconds and at the end it reads ``GET /api/health`` and checks: the
station's processes alive and not restarted, ``ok`` true, world-model and control above
``--min-hz``, the world still following the simulator (robots present, world seq
increasing). At the end the counts by reason (relay and backend) must account for what was
sent: counted <= expected, and expected - counted <= what was lost on the way (kernel drops of
the relay's sockets from /proc/net/udp, ZeroMQ losses between relay and backend, and what the
backend counted as "backend behind": overwritten on its bus before it was decoded). Prints a
table; exits 1 on any failure.

Figures (2-core machine, 10^6 datagrams): see tests/fuzz/README.md.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import re
import socket
import struct
import sys
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from backend.world.referee import decode_referee  # noqa: E402
from launcher.started import Started, start_isolated  # noqa: E402
from sslnet import streams  # noqa: E402
from sslnet.multicast import open_multicast_sender  # noqa: E402
from sslnet.streams import parse_message as parse_into  # noqa: E402
from sslnet.wire import key, varint  # noqa: E402
from sslpb.ssl_gc_referee_message_pb2 import Referee  # noqa: E402
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket  # noqa: E402

MAX_DATAGRAM = 32768  # the relay's --max-datagram default
ACCEPTED = "accepted"
WORLD_TIME = "world: " + streams.TIME_OUT_OF_RANGE

VISION_KINDS = {  # kind: weight
    "random bytes": 12, "truncated": 12, "byte flips": 14, "missing required": 10,
    "oversized": 0.05, "empty": 4, "bad utf-8": 6, "enum out of range": 6,
    "nan/inf coordinates": 10, "huge repeated": 3, "no content": 4,
}
REFEREE_KINDS = {
    "random bytes": 12, "truncated": 12, "byte flips": 14, "missing required": 10,
    "oversized": 0.05, "empty": 4, "bad utf-8": 8, "enum out of range": 10,
    "nan/inf coordinates": 6, "huge repeated": 3,
}


# --------------------------------------------------------------------------- datagrams

def _weird_float(rng: random.Random) -> float:
    return rng.choice([math.nan, math.inf, -math.inf, 1e308, -1e308, 3.4e38, -0.0])


def valid_wrapper(rng: random.Random, *, robots: int = 6, geometry: bool = False,
                  camera: int | None = None) -> SSL_WrapperPacket:
    """A detection (or geometry) packet whose capture time is random: it parses, and the
    world model drops it as "time out of range"."""
    w = SSL_WrapperPacket()
    d = w.detection
    d.frame_number = rng.randrange(1 << 31)
    d.t_capture = rng.uniform(0, 1e9)
    d.t_sent = d.t_capture + 0.001
    d.camera_id = rng.randrange(8) if camera is None else camera
    for _ in range(rng.randrange(2)):
        b = d.balls.add()
        b.confidence, b.x, b.y, b.pixel_x, b.pixel_y = 0.9, rng.uniform(-4500, 4500), \
            rng.uniform(-3000, 3000), 1.0, 1.0
    for i in range(robots):
        r = (d.robots_blue if i % 2 else d.robots_yellow).add()
        r.confidence, r.robot_id, r.x, r.y, r.orientation = 0.9, rng.randrange(16), \
            rng.uniform(-4500, 4500), rng.uniform(-3000, 3000), rng.uniform(-3, 3)
        r.pixel_x = r.pixel_y = 1.0
    if geometry:
        g = w.geometry.field
        g.field_length, g.field_width, g.goal_width, g.goal_depth, g.boundary_width = \
            9000, 6000, 1000, 180, 300
        ln = g.field_lines.add()
        ln.name = "TopTouchLine"
        ln.p1.x, ln.p1.y, ln.p2.x, ln.p2.y, ln.thickness = -4500, 3000, 4500, 3000, 10
    return w


def valid_referee(rng: random.Random) -> Referee:
    """One game controller's message: the same stage and command every time (a referee
    whose stage and command change at every datagram is a spoofed game controller, not a
    malformed datagram: it makes the recorder start a new file per stage change)."""
    r = Referee()
    r.packet_timestamp = int(time.time() * 1e6)
    r.stage = Referee.NORMAL_FIRST_HALF
    r.command = Referee.STOP
    r.command_counter = 1
    r.command_timestamp = r.packet_timestamp
    r.source_identifier = "fuzz"
    for t in (r.yellow, r.blue):
        t.name, t.score, t.red_cards, t.yellow_cards = "TeamName", 0, 0, 0
        t.timeouts, t.timeout_time, t.goalkeeper = 4, 300_000_000, 0
    return r


def _valid_bytes(stream: str, rng: random.Random) -> bytes:
    if stream == "vision":
        return valid_wrapper(rng, geometry=rng.random() < 0.2).SerializeToString()
    return valid_referee(rng).SerializeToString()


def make_datagram(stream: str, kind: str, rng: random.Random) -> bytes:
    """One datagram of ``kind`` for ``stream`` ("vision" or "referee")."""
    if kind == "random bytes":
        return rng.randbytes(rng.randrange(1, 400))
    if kind == "empty":
        return b""
    if kind == "truncated":
        v = _valid_bytes(stream, rng)
        return v[:rng.randrange(1, len(v))]
    if kind == "byte flips":
        b = bytearray(_valid_bytes(stream, rng))
        for _ in range(rng.randrange(1, 6)):
            i = rng.randrange(len(b))
            b[i] ^= 1 << rng.randrange(8) if rng.random() < 0.7 else rng.randrange(1, 256)
        return bytes(b)
    if kind == "oversized":
        base = _valid_bytes(stream, rng)
        # an unknown length-delimited field pads it past the limit: well-formed protobuf
        pad = rng.randrange(MAX_DATAGRAM + 1, 60000) - len(base) - 8
        return base + key(1000, 2) + varint(pad) + b"\0" * pad
    if kind == "no content":
        w = SSL_WrapperPacket()
        return w.SerializeToString() + key(900, 0) + varint(1)  # only an unknown field
    if stream == "vision":
        return _vision_kind(kind, rng)
    return _referee_kind(kind, rng)


def _vision_kind(kind: str, rng: random.Random) -> bytes:
    w = valid_wrapper(rng, geometry=kind == "bad utf-8")
    if kind == "missing required":
        d = w.detection
        d.ClearField(rng.choice(["frame_number", "t_capture", "t_sent", "camera_id"]))
        if rng.random() < 0.5 and len(d.robots_blue):
            d.robots_blue[0].ClearField("x")
        return w.SerializePartialToString()
    if kind == "bad utf-8":
        raw = w.SerializeToString()
        return raw.replace(b"TopTouchLine", rng.choice(
            [b"Top\xffTouchLin", b"\xc3(TouchLine1", b"\xed\xa0\x80TouchLine"]))
    if kind == "enum out of range":
        return _with_bad_shape(w, rng)  # SSL_FieldShapeType of a field line = 99..2^31
    if kind == "nan/inf coordinates":
        d = w.detection
        for r in list(d.robots_blue) + list(d.robots_yellow):
            if rng.random() < 0.7:
                r.x, r.y = _weird_float(rng), _weird_float(rng)
            if rng.random() < 0.3:
                r.orientation = _weird_float(rng)
        b = d.balls.add()
        b.confidence, b.pixel_x, b.pixel_y = 0.5, 0, 0
        b.x, b.y = _weird_float(rng), _weird_float(rng)
        if rng.random() < 0.3:
            d.t_capture = _weird_float(rng)
        return w.SerializeToString()
    if kind == "huge repeated":
        return valid_wrapper(rng, robots=rng.randrange(200, 700)).SerializeToString()
    raise ValueError(kind)


def _with_bad_shape(w: SSL_WrapperPacket, rng: random.Random) -> bytes:
    """``w`` with a field line whose shape type (an enum) is out of range."""
    g = w.geometry.field
    g.field_length, g.field_width, g.goal_width, g.goal_depth, g.boundary_width = \
        9000, 6000, 1000, 180, 300
    ln = g.field_lines.add()
    ln.name = "CenterLine"
    ln.p1.x, ln.p1.y, ln.p2.x, ln.p2.y, ln.thickness = 0, -3000, 0, 3000, 10
    raw = ln.SerializeToString() + key(4, 0) + varint(rng.choice([99, 999, 1 << 31]))
    del g.field_lines[-1]
    # re-nest by hand: field_lines is field 6 of SSL_GeometryFieldSize, field 1 of geometry,
    # geometry is field 2 of the wrapper
    gfield = g.SerializeToString() + key(6, 2) + varint(len(raw)) + raw
    geo = key(1, 2) + varint(len(gfield)) + gfield
    w.ClearField("geometry")
    return w.SerializeToString() + key(2, 2) + varint(len(geo)) + geo


def _referee_kind(kind: str, rng: random.Random) -> bytes:
    r = valid_referee(rng)
    if kind == "missing required":
        which = rng.choice(["packet_timestamp", "stage", "command", "command_counter",
                            "command_timestamp", "yellow", "blue", "team"])
        if which == "team":
            r.yellow.ClearField(rng.choice(["name", "score", "goalkeeper", "timeouts"]))
        else:
            r.ClearField(which)  # type: ignore[arg-type]
        return r.SerializePartialToString()
    if kind == "bad utf-8":
        raw = r.SerializeToString()
        return raw.replace(b"TeamName", rng.choice(
            [b"Team\xffNam", b"\xc3(amName", b"\xed\xa0\x80mName"]), 1)
    if kind == "enum out of range":
        # a required enum (closed, proto2) out of range: missing; an optional one: unknown
        which = rng.choice(["command", "stage", "next_command"])
        no = Referee.DESCRIPTOR.fields_by_name[which].number
        bad = key(no, 0) + varint(rng.choice([99, 1 << 20]))
        if which == "next_command" or rng.random() < 0.5:
            # a valid value first, then the out-of-range one (kept as an unknown field)
            return r.SerializeToString() + bad
        r.ClearField(which)  # type: ignore[arg-type]  # only the out-of-range value: the required field is missing
        return r.SerializePartialToString() + bad
    if kind == "nan/inf coordinates":
        r.designated_position.x = _weird_float(rng)
        r.designated_position.y = _weird_float(rng)
        return r.SerializeToString()
    if kind == "huge repeated":
        for _ in range(rng.randrange(500, 3000)):
            r.yellow.yellow_card_times.append(rng.randrange(1 << 30))
        return r.SerializeToString()
    raise ValueError(kind)


def expected_reason(stream: str, data: bytes) -> str:
    """Where ``data`` should be counted: "relay.<reason>", "<reason>" (backend) or
    ACCEPTED (parses and is used), "<reason>+accepted" for a bad string (used all the same),
    WORLD_TIME for a detection the world model drops (random capture time)."""
    if not data:
        return "relay." + streams.NO_CONTENT
    if len(data) > MAX_DATAGRAM:
        return "relay." + streams.OVERSIZED
    if stream == "vision":
        pkt = SSL_WrapperPacket()
        why = parse_into(pkt, data)
        if why is not None:
            return why[0]
        if not (pkt.HasField("detection") or pkt.HasField("geometry")):
            return streams.NO_CONTENT
        tags = []
        if pkt.HasField("geometry"):
            from backend.world.decode import geometry_to_dict
            bad: list[str] = []
            geometry_to_dict(pkt.geometry, bad)
            if bad:
                tags.append(streams.BAD_STRING)
        if pkt.HasField("detection"):
            tags.append(WORLD_TIME)
        return "+".join(tags) or ACCEPTED
    ref = Referee()
    why = parse_into(ref, data)
    if why is not None:
        return why[0]
    bad_r: list[str] = []
    decode_referee(ref, bad_r)
    return streams.BAD_STRING if bad_r else ACCEPTED


@dataclass
class Entry:
    stream: str
    kind: str
    data: bytes
    expect: str


def build_pool(seed: int, size: int, only: set[str] | None = None) -> list[Entry]:
    """``size`` datagrams, 70 % vision, 30 % referee (``only``: these kinds, for a diagnosis)."""
    rng = random.Random(seed)
    pool: list[Entry] = []
    for stream, kinds in (("vision", VISION_KINDS), ("referee", REFEREE_KINDS)):
        n = int(size * (0.7 if stream == "vision" else 0.3))
        names = [k for k in kinds if only is None or k in only]
        if not names:
            continue
        weights = [kinds[k] for k in names]
        made = rng.choices(names, weights, k=n)
        # at least a few of every kind
        made += [k for k in names for _ in range(2)]
        for kind in made:
            data = make_datagram(stream, kind, rng)
            pool.append(Entry(stream, kind, data, expected_reason(stream, data)))
    return pool


# --------------------------------------------------------------------------- the station

class Station(Started):
    def get(self, path: str) -> Any:
        r = httpx.get(self.url + path, timeout=10.0)
        r.raise_for_status()
        return r.json()


def launch(extra: list[str]) -> Station:
    try:
        st = start_isolated(extra)
    except RuntimeError as exc:
        raise SystemExit(str(exc)) from None
    return Station(**vars(st))


def kernel_drops(group: str, port: int) -> tuple[int, int]:
    """(sockets, drops) of the UDP sockets bound to group:port (/proc/net/udp)."""
    addr = struct.unpack("<I", socket.inet_aton(group))[0]
    want = f"{addr:08X}:{port:04X}"
    n = drops = 0
    with open("/proc/net/udp") as f:
        next(f)
        for line in f:
            cols = line.split()
            if cols[1] == want:
                n += 1
                drops += int(cols[-1])
    return n, drops


# --------------------------------------------------------------------------- checks

@dataclass
class Sample:
    t: float
    phase: str
    ok: bool
    warnings: list[str]
    hz: dict[str, float]
    world_seq: int
    robots: int
    restarts: int
    alive: bool
    load: float  # the machine's 1-minute load average (a shared machine: others' work too)
    world_hz: float = math.nan  # world updates/s since the previous sample (set in account)


def sample(st: Station, t0: float, phase: str) -> Sample:
    h = st.get("/api/health")
    w = st.get("/api/world")
    hz = {p["name"]: float(p["measured_hz"]) for p in h["processors"]}
    restarts = sum(int(c.get("restarts", 0)) for c in h.get("supervisor") or [])
    alive = True
    for pid in st.pids.values():
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            alive = False
    return Sample(time.monotonic() - t0, phase, bool(h["ok"]), list(h["warnings"]), hz,
                  int(w.get("seq", 0)), len(w.get("robots") or []), restarts, alive,
                  os.getloadavg()[0])


def counters(st: Station) -> dict[str, Any]:
    h = st.get("/api/health")
    out: dict[str, Any] = {"streams": h["streams"]}
    out["topics"] = {t["name"]: t["seq"] for t in h["topics"]}
    return out


def delta_reasons(a: dict[str, Any], b: dict[str, Any], name: str) -> Counter[str]:
    ra = Counter(a["streams"].get(name, {}).get("errors_by_reason", {}))
    rb = Counter(b["streams"].get(name, {}).get("errors_by_reason", {}))
    rb.subtract(ra)
    return Counter({k: v for k, v in rb.items() if v})


def stream_total(c: dict[str, Any], name: str, key: str) -> int:
    return int(c["streams"].get(name, {}).get(key, 0))


# --------------------------------------------------------------------------- main

def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=1_000_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--rate", type=float, default=4000.0,
                    help="datagrams per second (0: as fast as the kernel takes them)")
    ap.add_argument("--pool", type=int, default=4000, help="distinct datagrams to draw from")
    ap.add_argument("--check-every", type=float, default=10.0)
    ap.add_argument("--min-hz", type=float, default=40.0)
    ap.add_argument("--settle", type=float, default=3.0, help="seconds before and after")
    ap.add_argument("--json", type=Path, help="write the figures here")
    ap.add_argument("--only", help="comma-separated kinds (diagnosis), e.g. 'huge repeated'")
    args = ap.parse_args(argv)

    t_build = time.monotonic()
    pool = build_pool(args.seed, args.pool,
                      set(args.only.split(",")) if args.only else None)
    print(f"pool: {len(pool)} distinct datagrams in {time.monotonic() - t_build:.1f} s",
          flush=True)
    st = launch([])
    failures: list[str] = []
    samples: list[Sample] = []
    t0 = time.monotonic()
    try:
        ports = st.ports
        dest = {"vision": (ports["vision_group"], int(ports["vision"])),
                "referee": (ports["referee_group"], int(ports["referee"]))}
        time.sleep(args.settle)
        samples.append(sample(st, t0, "before"))
        before = counters(st)
        drops0 = {s: kernel_drops(*dest[s]) for s in dest}
        tx = open_multicast_sender("127.0.0.1", ttl=0)
        tx.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 1 << 20)
        rng = random.Random(args.seed + 1)
        sent: Counter[tuple[str, str]] = Counter()  # (stream, kind)
        expect: Counter[tuple[str, str]] = Counter()  # (stream, expected reason)
        send_blocked = 0
        batch = max(1, int(args.rate / 100)) if args.rate > 0 else 256
        t_send = time.monotonic()
        next_check = t_send + args.check_every
        done = 0
        while done < args.count:
            n = min(batch, args.count - done)
            for e in rng.choices(pool, k=n):
                while True:
                    try:
                        tx.sendto(e.data, dest[e.stream])
                        break
                    except BlockingIOError:
                        send_blocked += 1
                        time.sleep(0.0005)
                sent[(e.stream, e.kind)] += 1
                expect[(e.stream, e.expect)] += 1
            done += n
            now = time.monotonic()
            if args.rate > 0:
                ahead = t_send + done / args.rate - now
                if ahead > 0:
                    time.sleep(ahead)
            if now >= next_check:
                s = sample(st, t0, "during")
                samples.append(s)
                print(f"  {done:>9} sent, {done / (now - t_send):7.0f}/s  ok={s.ok} "
                      f"world-model {s.hz.get('world-model', 0):.0f} Hz control "
                      f"{s.hz.get('control', 0):.0f} Hz robots {s.robots} seq {s.world_seq}",
                      flush=True)
                next_check = now + args.check_every
        send_s = time.monotonic() - t_send
        tx.close()
        samples.append(sample(st, t0, "during"))
        time.sleep(args.settle)  # the backend works off what is queued
        after = counters(st)
        drops1 = {s: kernel_drops(*dest[s]) for s in dest}
        time.sleep(args.settle)
        samples.append(sample(st, t0, "after"))
        samples.append(sample(st, t0, "after"))
        exit_code = st.stop(20)
        report = account(args, sent, expect, before, after, drops0, drops1, send_s,
                         send_blocked, samples, failures)
        if exit_code not in (0, None):
            failures.append(f"the launcher exited with {exit_code}")
        elif exit_code is None:
            failures.append("the launcher did not stop within 20 s of SIGTERM")
        if args.json:
            args.json.write_text(json.dumps(report, indent=1))
    except BaseException:
        st.stop(20)
        print("\n".join(st.lines[-40:]), file=sys.stderr)
        raise
    if failures:
        print("\nFAILED:")
        for f in failures:
            print("  - " + f)
        print("\nstation log (tail):\n" + "\n".join(st.lines[-30:]))
        return 1
    print("\nPASS: 0 crashes, every malformed datagram counted or accounted as lost")
    return 0


def account(args: argparse.Namespace, sent: Counter[tuple[str, str]],
            expect: Counter[tuple[str, str]], before: dict[str, Any], after: dict[str, Any],
            drops0: dict[str, tuple[int, int]], drops1: dict[str, tuple[int, int]],
            send_s: float, send_blocked: int, samples: list[Sample],
            failures: list[str]) -> dict[str, Any]:
    total = sum(sent.values())
    print(f"\nsent {total} malformed datagrams in {send_s:.1f} s: {total / send_s:.0f}/s "
          f"(sender blocked {send_blocked} times)")
    print("\n  stream   kind                   sent")
    for (s_name, k), n in sorted(sent.items()):
        print(f"  {s_name:8} {k:22} {n:8}")
    report: dict[str, Any] = {"sent": total, "send_s": send_s, "rate": total / send_s,
                              "kinds": {f"{sn}/{k}": n for (sn, k), n in sent.items()},
                              "streams": {}}
    for stream in ("vision", "referee"):
        exp: Counter[str] = Counter()
        for (s_name, e_reason), n in expect.items():
            if s_name == stream:
                for part in e_reason.split("+"):
                    exp[part] += n
        relay_in = (stream_total(after, f"relay.{stream}", "packets")
                    + stream_total(after, f"relay.{stream}", "errors")
                    - stream_total(before, f"relay.{stream}", "packets")
                    - stream_total(before, f"relay.{stream}", "errors"))
        forwarded = (stream_total(after, f"relay.{stream}", "packets")
                     - stream_total(before, f"relay.{stream}", "packets"))
        processed = (stream_total(after, stream, "packets")
                     - stream_total(before, stream, "packets"))
        bus = after["topics"][f"{stream}-packets"] - before["topics"][f"{stream}-packets"]
        kdrops = drops1[stream][1] - drops0[stream][1]
        sent_s = sum(n for (s_name, _), n in sent.items() if s_name == stream)
        lost_backend = forwarded - processed  # the ingests count what the bus overwrote
        counted: Counter[str] = Counter()
        for reason, n in delta_reasons(before, after, f"relay.{stream}").items():
            counted["relay." + reason] += n
        for reason, n in delta_reasons(before, after, stream).items():
            counted[WORLD_TIME if reason == streams.TIME_OUT_OF_RANGE and stream == "vision"
                    else reason] += n
        print(f"\n{stream}: sent {sent_s}, relay received {relay_in} (incl. the simulator's), "
              f"kernel dropped {kdrops} ({drops1[stream][0]} socket(s)), relay forwarded "
              f"{forwarded}, on the backend bus {bus}, counted by the ingest {processed} "
              f"(lost relay->backend {lost_backend}: {forwarded - bus} in ZeroMQ, "
              f"{bus - processed} on the bus, never counted)")
        print(f"  {'reason':34} {'expected':>9} {'counted':>9}")
        # what the bus overwrote before the ingest decoded it is counted ("backend behind"):
        # lost for the reasons, whatever they would have been (the simulator's frames too)
        behind = counted.pop(streams.BEHIND, 0)
        lost = max(0, kdrops) + max(0, forwarded - bus) + behind
        print(f"  {streams.BEHIND + ' (counted, lost)':34} {'-':>9} {behind:9}")
        missing_total = 0
        rows: dict[str, dict[str, int]] = {streams.BEHIND: {"expected": 0, "counted": behind}}
        for reason in sorted(set(exp) | set(counted)):
            if reason == ACCEPTED:
                continue
            n_exp, n_cnt = exp.get(reason, 0), counted.get(reason, 0)
            rows[reason] = {"expected": n_exp, "counted": n_cnt}
            print(f"  {reason:34} {n_exp:9} {n_cnt:9}")
            if n_cnt > n_exp * 1.02 + 5:
                failures.append(f"{stream}: {reason}: counted {n_cnt} > expected {n_exp}")
            if n_exp > 0 and n_cnt == 0 and n_exp > lost:
                failures.append(f"{stream}: {reason}: {n_exp} sent, none counted")
            missing_total += max(0, n_exp - n_cnt)
        print(f"  {ACCEPTED + ' (parses, used)':34} {exp.get(ACCEPTED, 0):9}")
        print(f"  expected - counted: {missing_total}; lost on the way: {lost}")
        if missing_total > lost * 1.05 + 10:
            failures.append(f"{stream}: {missing_total} malformed datagrams not counted, only "
                            f"{lost} lost on the way")
        report["streams"][stream] = {
            "sent": sent_s, "relay_received": relay_in, "kernel_drops": kdrops,
            "forwarded": forwarded, "bus": bus, "decoded": processed,
            "lost_relay_backend": lost_backend, "lost_zmq": forwarded - bus,
            "lost_bus_ring": bus - processed, "reasons": rows,
            "accepted": exp.get(ACCEPTED, 0), "uncounted": missing_total}
    # world Hz: world updates per second since the previous sample (the processors'
    # measured_hz counts ticks, and the world model also ticks for frames it drops)
    print(f"\n  {'t (s)':>6} {'phase':7} {'ok':5} {'world-model':>11} {'control':>8} "
          f"{'world Hz':>8} {'robots':>6} {'world seq':>9} restarts alive  load")
    prev: Sample | None = None
    for s in samples:
        world_hz = ((s.world_seq - prev.world_seq) / (s.t - prev.t)
                    if prev is not None and s.t - prev.t >= 1.0 else math.nan)
        s.world_hz = world_hz
        print(f"  {s.t:6.0f} {s.phase:7} {s.ok!s:5} {s.hz.get('world-model', 0):11.0f} "
              f"{s.hz.get('control', 0):8.0f} {world_hz:8.0f} {s.robots:6} {s.world_seq:9} "
              f"{s.restarts:8} {s.alive!s:5} {s.load:5.1f}")
        for name in ("world-model", "control"):
            if s.hz.get(name, 0) < args.min_hz:
                failures.append(f"t={s.t:.0f} s: {name} at {s.hz.get(name, 0):.0f} Hz "
                                f"< {args.min_hz:.0f}")
        if world_hz < args.min_hz:  # False for NaN
            failures.append(f"t={s.t:.0f} s: the world updated at {world_hz:.0f} Hz "
                            f"< {args.min_hz:.0f}")
        if not s.ok:
            failures.append(f"t={s.t:.0f} s: health not ok: {s.warnings}")
        if s.restarts:
            failures.append(f"t={s.t:.0f} s: {s.restarts} restart(s)")
        if not s.alive:
            failures.append(f"t={s.t:.0f} s: a station process is gone")
        if s.robots == 0:
            failures.append(f"t={s.t:.0f} s: no robots in the world")
        if prev is not None and s.world_seq <= prev.world_seq:
            failures.append(f"t={s.t:.0f} s: world seq did not increase ({s.world_seq})")
        prev = s
    warnings = Counter(re.sub(r"[-+]?\d[\d.]*", "N", w) for s in samples for w in s.warnings)
    if warnings:
        print("  warnings seen (samples): " + "; ".join(f"{w} ({n})"
                                                       for w, n in sorted(warnings.items())))
    report["samples"] = [s.__dict__ for s in samples]
    return report


if __name__ == "__main__":
    sys.exit(main())
