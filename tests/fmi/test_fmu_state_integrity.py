"""Damaged and crafted FMU states are refused with a logged reason, never used (issue 15).

Every shipped FMU (accel9, sins, the three gyro-free navigators, vehicle, transfer
alignment; FMI 2.0 and 3.0) is run a few steps, its state serialized, and the body of the serialized state
damaged while the header (magic, format, size, instantiation token) is kept:

* damaged:  the model data replaced by random bytes, or one bit flipped anywhere in the
            body; the header's CRC-32 no longer matches, deserialization must refuse it;
* crafted:  the same random model data with the CRC-32 recomputed (a crafted file): the
            per-model validation must refuse it;
* sparse:   a few random bytes of the model data changed and the CRC recomputed: the
            state may be plausible, so it may be accepted, but nothing may crash and a
            following doStep returns OK or an error.

A refused state leaves the instance as it was: the next doStep at its current time
succeeds. Each FMU runs in a forked child process, so that a crash (the behaviour before
this check existed: a scrambled sins or gyro-free state segfaulted in doStep) fails the
test with the case that crashed instead of killing pytest.

Truth for the integrity check is zlib.crc32 (the IEEE 802.3 CRC-32) over the body as
docs/fmu.md describes the serialized format; the glue's own CRC is not used here.
"""
from __future__ import annotations

import multiprocessing
import struct
import zlib

import numpy as np
import pytest

from gfins_fmi.fmi.runner import FmuLog, FmuSlave
from gfins_fmi.fmi.paths import fmu_path

H_S = 0.01
N_STEPS = 5
# FmuSnapshot (fmu/glue/fmu_instance.h) starts with mode, stop_time_defined (uint32, int32)
# and the start, stop and current times (3 doubles): 32 bytes checked since the first
# version; the model data (ModelData) follows them and is what gets damaged here.
SNAPSHOT_PREFIX = 32
# serialized header (docs/fmu.md): magic[8], format u32, snapshot size u32, CRC-32 u32,
# reserved u32, token[48]
HEADER_FORMAT_AT, HEADER_SIZE_AT, HEADER_CRC_AT = 8, 12, 16

# a stable low-pass section [b0 b1 b2 1 a1 a2] (|a2| < 1, |a1| < 1 + a2) so that the SINS
# state carries a live filter; IMU compensation on with the default (zero) errors
_SOS = [0.2, 0.4, 0.2, 1.0, -0.5, 0.3] + [0.0] * 42
SETUPS = {
    "accel9": ({"l": 0.1}, {"A": np.zeros(9)}),
    "sins": ({"imu_comp": 1, "lowpass_sections": 1, "lowpass_sos": _SOS, "vertical_mode": 1},
             {"dtheta": np.zeros(3), "dv": np.array([0.0, 0.0, 9.8 * H_S])}),
    "gfnav_cube6": ({}, {"A": np.zeros(6)}),
    "gfnav_qin9": ({"strategy": 3}, {"A": np.zeros(9)}),   # fused: the Kalman state is live
    "gfnav_12": ({}, {"A": np.zeros(12)}),
    "vehicle": ({"imu_errors": 1, "noise": 1, "gyro_arw": 1e-4, "accel_vrw": 1e-4,
                 "array_noise": 1e-4}, {}),
    # every transfer-alignment state live (38 with the flexure and scale factors)
    "transfer_align": ({"master_mount": 1, "master_lever": 1, "master_time_offset": 1, "flexure": 1,
                        "scale_factors": 1},
                       {"dtheta": np.zeros(3), "dv": np.array([0.0, 0.0, 9.8 * H_S])}),
}


def _fmi(slave, name2: str, name3: str):
    return getattr(slave.slave, name2 if slave.version == 2 else name3)


def _split(blob: bytes) -> tuple[bytes, bytearray]:
    size = struct.unpack_from("<I", blob, HEADER_SIZE_AT)[0]
    assert 0 < size < len(blob), "the header's snapshot size does not fit the blob"
    return blob[:len(blob) - size], bytearray(blob[len(blob) - size:])


def _with_crc(header: bytes, body: bytes) -> bytes:
    h = bytearray(header)
    struct.pack_into("<I", h, HEADER_CRC_AT, zlib.crc32(body))
    return bytes(h) + bytes(body)


def _cases(blob: bytes, seed: int) -> list[tuple[str, bytes]]:
    """(kind, bytes) of the damaged states made from a good serialized state."""
    header, body = _split(blob)
    rng = np.random.default_rng(seed)
    out = []
    for i in range(2):
        b = bytearray(body)
        b[SNAPSHOT_PREFIX:] = rng.integers(0, 256, len(b) - SNAPSHOT_PREFIX, dtype=np.uint8).tobytes()
        out.append((f"damaged: model data random ({i})", header + bytes(b)))
        out.append((f"crafted: model data random, CRC recomputed ({i})", _with_crc(header, b)))
    for pos in rng.integers(0, len(body), 4):
        b = bytearray(body)
        b[pos] ^= 1 << int(rng.integers(0, 8))
        out.append((f"damaged: one bit flipped at body byte {pos}", header + bytes(b)))
    for i in range(6):
        b = bytearray(body)
        for pos in rng.integers(SNAPSHOT_PREFIX, len(b), 8):
            b[pos] = int(rng.integers(0, 256))
        out.append((f"sparse: 8 bytes changed, CRC recomputed ({i})", _with_crc(header, b)))
    return out


def _run_model(model: str, version: int, conn) -> None:
    """Child process: runs every case of one FMU and sends one result dict per case."""
    params, inputs = SETUPS[model]
    log = FmuLog()
    s = FmuSlave(fmu_path(model, version), version, log, logging_on=False)
    try:
        s.initialize(0.0, 1.0, params)
        t = 0.0

        def step() -> bool:
            nonlocal t
            for name, value in inputs.items():
                s.set(name, value)
            try:
                s.slave.doStep(currentCommunicationPoint=t, communicationStepSize=H_S)
            except Exception:
                return False
            t += H_S
            return True

        for _ in range(N_STEPS):
            assert step(), f"{model}: doStep failed before the test: {log.messages}"
        good = _fmi(s, "getFMUstate", "getFMUState")()
        blob = bytes(_fmi(s, "serializeFMUstate", "serializeFMUState")(good))
        header, body = _split(blob)
        conn.send({"kind": "format", "format": struct.unpack_from("<I", header, HEADER_FORMAT_AT)[0],
                   "crc": struct.unpack_from("<I", header, HEADER_CRC_AT)[0],
                   "crc_expected": zlib.crc32(body)})
        t_good = t
        for kind, data in _cases(blob, seed=10 * list(SETUPS).index(model) + version):
            conn.send({"kind": kind, "started": True})   # so that a crash names its case
            log.messages.clear()
            result = {"kind": kind, "refused": False, "step_ok": None}
            try:
                st = _fmi(s, "deSerializeFMUstate", "deserializeFMUState")(data)
            except Exception:
                result["refused"] = True
            else:
                try:
                    _fmi(s, "setFMUstate", "setFMUState")(st)
                except Exception:
                    result["refused"] = True
                _fmi(s, "freeFMUstate", "freeFMUState")(st)
                if not result["refused"]:
                    t = struct.unpack_from("<d", data, len(header) + 24)[0]   # the state's time
                    result["step_ok"] = step()
                    _fmi(s, "setFMUstate", "setFMUState")(good)
            result["log"] = list(log.messages)
            t = t_good
            result["usable"] = step()   # a refused state left the instance as it was
            _fmi(s, "setFMUstate", "setFMUState")(good)
            t = t_good
            conn.send(result)
        _fmi(s, "freeFMUstate", "freeFMUState")(good)
    finally:
        s.close()
        conn.send({"kind": "done"})
        conn.close()


def _results(model: str, version: int) -> list[dict]:
    ctx = multiprocessing.get_context("fork")
    parent, child = ctx.Pipe(duplex=False)
    p = ctx.Process(target=_run_model, args=(model, version, child))
    p.start()
    child.close()
    got, current = [], None
    while True:
        try:
            msg = parent.recv()
        except EOFError:
            break
        if msg.get("started"):
            current = msg["kind"]
            continue
        got.append(msg)
        current = None
    p.join(60)
    assert p.exitcode == 0, (f"FMI {version}.0 {model}: the process died (exit code {p.exitcode}) "
                             f"in case {current!r}: a damaged state was used")
    assert got and got[-1]["kind"] == "done"
    return got[:-1]


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("model", list(SETUPS))
def test_damaged_states_are_refused(model, version):
    res = _results(model, version)
    fmt, cases = res[0], res[1:]
    for r in cases:
        kind = r["kind"]
        if kind.startswith("sparse"):
            # plausible states may be accepted; then the step returned (no crash) and a good
            # state restores the instance
            assert r["refused"] or r["step_ok"] in (True, False), kind
        else:
            assert r["refused"], f"FMI {version}.0 {model}: {kind} was accepted"
            text = " ".join(r["log"])
            assert "deserializ" in text.lower(), f"{kind}: no logged reason: {r['log']}"
            if kind.startswith("damaged"):
                assert "CRC" in text, f"{kind}: the reason does not name the integrity check: {text}"
            else:
                assert "refused" in text, f"{kind}: the reason does not say what was refused: {text}"
        assert r["usable"], f"FMI {version}.0 {model}: after {kind} the instance cannot step: {r['log']}"
    assert fmt["format"] == 2, "serialized state format 2 (with CRC-32) expected"
    assert fmt["crc"] == fmt["crc_expected"], "header CRC-32 differs from zlib.crc32 of the body"
