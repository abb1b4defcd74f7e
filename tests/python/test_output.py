# SPDX-License-Identifier: BSD-3-Clause
""".afsim output from Python: written frames read back exactly, checks on bad input."""
import numpy as np
import pytest

import asyncfem as af


def test_write_and_read_back(tmp_path):
    path = tmp_path / "run.afsim"
    n = 5
    rng = np.random.default_rng(3)
    frames = [rng.standard_normal(3 * n) for _ in range(4)]
    velocities = [rng.standard_normal(3 * n) for _ in range(4)]
    header = af.SimulationFileHeader(num_vertices=n, frame_interval=0.1, timestep=0.01, has_velocities=True)
    with af.SimulationWriter(path, header) as writer:
        for k, (u, v) in enumerate(zip(frames, velocities)):
            writer.append_frame(0.1 * (k + 1), u, v)
        assert writer.num_frames == 4 and writer.header.record_bytes > 0
        with pytest.raises(ValueError, match="velocity: the header says frames carry velocities"):
            writer.append_frame(1.0, frames[0])
        with pytest.raises(ValueError, match=r"displacement: expected a float64 array of shape \(15,\)"):
            writer.append_frame(1.0, np.zeros(4), velocities[0])
    reader = af.SimulationReader(path)
    assert (reader.num_vertices, reader.num_frames, len(reader)) == (n, 4, 4)
    assert reader.header.frame_interval == 0.1 and reader.truncated_trailing_bytes == 0
    reader.verify_all()
    frame = reader.read_frame(2)
    assert frame.index == 2 and frame.time == pytest.approx(0.3, rel=1e-15)
    np.testing.assert_array_equal(frame.displacement, frames[2])  # stored as raw doubles: exact
    np.testing.assert_array_equal(frame.velocity, velocities[2])
    np.testing.assert_array_equal(reader.displacements(), np.array(frames))
    with pytest.raises(IndexError, match="frame 4 out of range"):
        reader.read_frame(4)


def test_refuses_non_finite_and_reads_truncated(tmp_path):
    path = tmp_path / "bad.afsim"
    writer = af.SimulationWriter(path, af.SimulationFileHeader(2, 0.5))
    writer.append_frame(0.5, np.zeros(6))
    with pytest.raises(af.Error, match="bad.afsim"):
        writer.append_frame(1.0, np.full(6, np.nan))
    writer.close()
    with open(path, "ab") as out:
        out.write(b"\0" * 10)  # an interrupted append
    reader = af.SimulationReader(path)
    assert reader.num_frames == 1 and reader.truncated_trailing_bytes == 10
    (tmp_path / "garbage.afsim").write_bytes(b"not a simulation file at all")
    with pytest.raises(af.ParseError):
        af.SimulationReader(tmp_path / "garbage.afsim")


def write_region_ratio_file(path, ratios_per_frame):
    """An .afsim file (version 1) whose records carry region ratios (flag bit 1), laid out
    as docs/simulation-output.md says: n u16 ratios after the displacement, padded to 8 bytes."""
    import struct
    import zlib

    n = len(ratios_per_frame[0])
    padding = -2 * n % 8
    record = 16 + 24 * n + 2 * n + padding + 8
    header = b"AFEMSIM\0" + struct.pack("<IIQddQQI", 1, 64, n, 0.1, 0.025, 2, record, 0)
    data = header + struct.pack("<I", zlib.crc32(header))
    for k, ratios in enumerate(ratios_per_frame):
        body = struct.pack("<qd", k, 0.1 * (k + 1)) + np.full(3 * n, 0.5 * k).astype("<f8").tobytes()
        body += np.array(ratios, dtype="<u2").tobytes() + b"\0" * padding
        data += body + struct.pack("<II", zlib.crc32(body), 0)
    path.write_bytes(data)


def test_region_ratios_read_back(tmp_path):
    path = tmp_path / "regions.afsim"
    ratios = [[1, 1, 8, 8, 1], [1, 8, 8, 8, 65535]]
    write_region_ratio_file(path, ratios)
    reader = af.SimulationReader(path)
    assert reader.header.has_region_ratios and reader.num_frames == 2
    np.testing.assert_array_equal(reader.read_frame(1).region_ratios, ratios[1])
    all_ratios = reader.region_ratios()
    assert all_ratios.dtype == np.uint16 and all_ratios.shape == (2, 5)
    np.testing.assert_array_equal(all_ratios, ratios)
    # A file without them: no ratios per frame, and region_ratios() says how to record them.
    plain = tmp_path / "plain.afsim"
    with af.SimulationWriter(plain, af.SimulationFileHeader(2, 0.5)) as writer:
        writer.append_frame(0.5, np.zeros(6))
    assert not af.SimulationReader(plain).header.has_region_ratios
    assert af.SimulationReader(plain).read_frame(0).region_ratios.size == 0
    with pytest.raises(ValueError, match=r'plain.afsim does not record region ratios .*"output": \{"regions": true\}'):
        af.SimulationReader(plain).region_ratios()
    # A ratio of 0 is named with its frame and vertex.
    write_region_ratio_file(path, [[1, 1, 8, 8, 1], [1, 8, 0, 8, 1]])
    with pytest.raises(af.ParseError, match="frame 1: vertex 2 has region ratio 0"):
        af.SimulationReader(path).verify_all()
