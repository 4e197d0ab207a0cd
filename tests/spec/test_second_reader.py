#!/usr/bin/python3
"""The spec is enough for a second implementation: scripts/vxl_spec_reader.py, a reader written from
spec/vxl-format.md alone (Python, no code shared with the C++ one), reads and checks what the converter writes.

Cases: a synthetic tractogram converted with each option that changes the bytes (position encoding, order set,
levels, voxel size), a hand-made one with a negative zero on the data's edge and long steps that end exactly
on voxel faces (spec §5.1, §6.3), and, with --real-data, every real tractogram the converter accepts. Each file
must pass the reader's checks (spec §7: open and verify) and, from a TCK, give back the source's points within
the precision policy (spec §8); a file with one byte flipped must be refused.

Usage: tests/spec/test_second_reader.py --voxlines PATH [--real-data DIR]
Exit 0 every case passes, 1 a case fails, 77 the synthetic cases pass but the real tractograms are absent.
"""
import argparse
import os
import struct
import sys
import tempfile

from spec_test_support import flip_middle_byte, readers_can_run, run

REPOSITORY = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
READER = os.path.join(REPOSITORY, "scripts", "vxl_spec_reader.py")
OPTION_SETS = {
    "default": [],
    "float32": ["--positions", "float32"],
    "axis_diag": ["--orders", "axis+diag"],
    "random_one_level": ["--orders", "random:4", "--positions", "float32", "--levels", "1"],
    "small_voxels": ["--voxel-size", "2.5"],
}
SOURCE_SUFFIXES = (".tck", ".trk", ".trk.gz", ".trx", ".vtk", ".vtp")


def write_tck(path, streamlines):
    """A Float32LE TCK of the given streamlines (lists of (x, y, z))."""
    header = "mrtrix tracks\ndatatype: Float32LE\ncount: %d\nfile: . %d\nEND\n"
    size = len(header % (len(streamlines), 0)) + 16
    with open(path, "wb") as f:
        f.write((header % (len(streamlines), size)).encode().ljust(size, b"\0"))
        for points in streamlines:
            for p in points:
                f.write(struct.pack("<3f", *p))
            f.write(struct.pack("<3f", float("nan"), float("nan"), float("nan")))
        f.write(struct.pack("<3f", float("inf"), float("inf"), float("inf")))


def edge_streamlines():
    # Starts at (-0, -0, -0): the grid's origin, stored as +0. With 10 mm voxels the steps from 0 to 30 and
    # from 30 back to 0 cross faces at t = 1 and t = 0, where the crossing point is a source point.
    return [[(-0.0, -0.0, -0.0), (30.0, 30.0, 30.0), (0.0, 30.0, 0.0)],
            [(1.0, 2.0, 3.0), (1.5, 2.5, 3.5), (25.0, 2.5, 3.5)]]


def check(voxlines, source, vxl, options, failures):
    """Converts `source` with `options` and runs the second reader on the result; returns False where the
    converter refuses the source (a malformed fixture: its refusal is tested elsewhere)."""
    converted = run([voxlines, "convert", source, vxl] + options)
    if converted.returncode != 0:
        return False
    command = [sys.executable, READER, vxl, "-q"]
    if source.endswith(".tck"):
        command += ["--compare", source]
    read = run(command)
    name = os.path.basename(vxl)
    if read.returncode != 0:
        failures.append(f"{name}: {read.stdout.strip()}")
    print(f"{name}: {'ok' if read.returncode == 0 else 'FAILED'}")
    return True


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--voxlines", required=True)
    parser.add_argument("--real-data", default="")
    options = parser.parse_args()
    if not readers_can_run():
        return 1
    failures = []
    with tempfile.TemporaryDirectory() as scratch:
        synth = os.path.join(scratch, "synth.tck")
        made = run([options.voxlines, "synth", synth, "--streamlines", "2000", "--seed", "3"])
        if made.returncode != 0:
            print(made.stdout)
            return 1
        for name, option_set in OPTION_SETS.items():
            if not check(options.voxlines, synth, os.path.join(scratch, f"synth_{name}.vxl"), option_set, failures):
                failures.append(f"synth_{name}: the converter refused the synthetic tractogram")
        # The reader can refuse: one flipped byte in the middle of a file it accepted must fail a checksum.
        damaged = os.path.join(scratch, "synth_default.vxl")
        flip_middle_byte(damaged)
        refused = run([sys.executable, READER, damaged, "-q"])
        print(f"synth_default.vxl with a flipped byte: {'refused' if refused.returncode == 1 else 'NOT refused'}")
        if refused.returncode != 1:
            failures.append(f"a damaged file was not refused (exit {refused.returncode}): {refused.stdout.strip()}")
        edges = os.path.join(scratch, "edges.tck")
        write_tck(edges, edge_streamlines())
        for name, option_set in (("packed", []), ("float32", ["--positions", "float32"])):
            if not check(options.voxlines, edges, os.path.join(scratch, f"edges_{name}.vxl"), option_set, failures):
                failures.append(f"edges_{name}: the converter refused the hand-made tractogram")

        real = options.real_data
        if not real or not os.path.isdir(real):
            print("real tractograms skipped: their folder (--real-data) is absent")
        else:
            accepted = 0
            for entry in sorted(os.listdir(real)):
                if entry.endswith(SOURCE_SUFFIXES):
                    vxl = os.path.join(scratch, entry.replace(".", "_") + ".vxl")
                    accepted += check(options.voxlines, os.path.join(real, entry), vxl, [], failures)
            if accepted == 0:
                failures.append(f"no real tractogram in {real} was converted")
    for failure in failures:
        print("FAILED", failure)
    if failures:
        return 1
    return 0 if real and os.path.isdir(real) else 77


if __name__ == "__main__":
    sys.exit(main())
