#!/usr/bin/python3
"""The package spec is enough for a second implementation: scripts/vxlz_spec_reader.py, a reader written from
spec/vxlz-package-v2.md and spec/vxl-format.md alone (Python, and libdraco through tests/spec/draco_cloud_dump.cpp;
no code shared with the C++ one), checks every package `voxlines pack` writes and decodes it into the .vxl that
`voxlines unpack` must give back, which it compares with the real one part by part.

Cases: a synthetic tractogram packed in level order (the default) and in streamline order (one level), at 11, 14
and 16 bits, with another order set, unpacked with packed and float32 positions and other level counts; with
--real-data, every real tractogram the converter accepts (groups, per-point and per-streamline values, TSF values,
synthetic face points, an empty file). A package with one byte flipped must be refused, and an unpacked file must
differ from another package's decoding.

Usage: tests/spec/test_second_package_reader.py --voxlines PATH --draco-dump PATH [--real-data DIR]
Exit 0 every case passes, 1 a case fails, 77 the synthetic cases pass but the real tractograms are absent.
"""
import argparse
import os
import sys
import tempfile

from spec_test_support import flip_middle_byte, readers_can_run, run

REPOSITORY = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
READER = os.path.join(REPOSITORY, "scripts", "vxlz_spec_reader.py")
SOURCE_SUFFIXES = (".tck", ".trk", ".trk.gz", ".trx", ".vtk", ".vtp")
# (name, convert options, pack options, unpack options)
SYNTHETIC_CASES = [
    ("default", [], [], []),
    ("default_float32", [], [], ["--positions", "float32"]),
    ("bits11", [], ["--bits", "11"], []),
    ("bits16_float32", [], ["--bits", "16"], ["--positions", "float32"]),
    ("one_level", ["--levels", "1"], [], []),
    ("one_level_unpacked_float32_one_level", ["--levels", "1"], [], ["--positions", "float32", "--levels", "1"]),
    ("unpacked_with_two_levels", [], [], ["--levels", "2"]),
    ("axis_diag_small_voxels", ["--orders", "axis+diag", "--voxel-size", "2.5", "--levels", "3"], ["--bits", "13"],
     ["--positions", "float32", "--levels", "4"]),
]
# Real sources whose values come from a separate file.
TSF_PAIRS = [("test_data__tracks.tck", "test_data__afd.tsf"), ("niivue__tract.SLF1_R.tck", "niivue__mni152.SLF1_R.tsf")]


class Checker:
    def __init__(self, voxlines, draco_dump, scratch):
        self.voxlines, self.draco_dump, self.scratch = voxlines, draco_dump, scratch
        self.failures = []

    def read(self, package, unpacked=None):
        command = [sys.executable, READER, package, "--draco-dump", self.draco_dump, "-q"]
        return run(command + (["--compare", unpacked] if unpacked else []))

    def check(self, name, source, convert=(), pack=(), unpack=()):
        """Converts, packs and unpacks `source`; the second reader must accept the package and find the unpacked
        file equal to its own decoding. Returns False where the converter refuses the source (a malformed
        fixture: its refusal is tested elsewhere) or cannot pack it."""
        base = os.path.join(self.scratch, name)
        if run([self.voxlines, "convert", source, base + ".vxl", *convert]).returncode != 0:
            return False
        packed = run([self.voxlines, "pack", base + ".vxl", base + ".vxlz", *pack])
        if packed.returncode != 0:
            self.failures.append(f"{name}: pack failed: {packed.stdout.strip()}")
            return True
        unpacked = run([self.voxlines, "unpack", base + ".vxlz", base + "_unpacked.vxl", *unpack])
        if unpacked.returncode != 0:
            self.failures.append(f"{name}: unpack failed: {unpacked.stdout.strip()}")
            return True
        read = self.read(base + ".vxlz", base + "_unpacked.vxl")
        if read.returncode != 0:
            self.failures.append(f"{name}: {read.stdout.strip()}")
        print(f"{name}: {'ok' if read.returncode == 0 else 'FAILED'}")
        return True

    def expect_refused(self, what, result):
        print(f"{what}: {'refused' if result.returncode == 1 else 'NOT refused'}")
        if result.returncode != 1:
            self.failures.append(f"{what}: not refused (exit {result.returncode}): {result.stdout.strip()}")


def check_real(checker, real):
    """Every real tractogram the converter accepts, and the TSF pairs; returns how many were converted."""
    accepted = 0
    for entry in sorted(os.listdir(real)):
        if entry.endswith(SOURCE_SUFFIXES):
            accepted += checker.check(entry.replace(".", "_"), os.path.join(real, entry))
    for tck, tsf in TSF_PAIRS:
        if os.path.exists(os.path.join(real, tck)) and os.path.exists(os.path.join(real, tsf)):
            accepted += checker.check(tsf.replace(".", "_"), os.path.join(real, tck), ["--tsf", os.path.join(real, tsf)],
                                      unpack=["--positions", "float32"])
    return accepted


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--voxlines", required=True)
    parser.add_argument("--draco-dump", required=True)
    parser.add_argument("--real-data", default="")
    options = parser.parse_args()
    if not readers_can_run():
        return 1
    with tempfile.TemporaryDirectory() as scratch:
        checker = Checker(options.voxlines, options.draco_dump, scratch)
        synth = os.path.join(scratch, "synth.tck")
        made = run([options.voxlines, "synth", synth, "--streamlines", "2000", "--seed", "3"])
        if made.returncode != 0:
            print(made.stdout)
            return 1
        for name, convert, pack, unpack in SYNTHETIC_CASES:
            if not checker.check("synth_" + name, synth, convert, pack, unpack):
                checker.failures.append(f"synth_{name}: the converter refused the synthetic tractogram")
        # The reader can tell: another package's unpacked file differs from this package's decoding, and one
        # flipped byte in the middle of a package it accepted fails a checksum.
        base = os.path.join(scratch, "synth_")
        checker.expect_refused("synth_default.vxlz against bits11's unpacked file",
                               checker.read(base + "default.vxlz", base + "bits11_unpacked.vxl"))
        flip_middle_byte(base + "default.vxlz")
        checker.expect_refused("synth_default.vxlz with a flipped byte", checker.read(base + "default.vxlz"))

        real = options.real_data
        if not real or not os.path.isdir(real):
            print("real tractograms skipped: their folder (--real-data) is absent")
        elif check_real(checker, real) == 0:
            checker.failures.append(f"no real tractogram in {real} was converted")
    for failure in checker.failures:
        print("FAILED", failure)
    if checker.failures:
        return 1
    return 0 if real and os.path.isdir(real) else 77


if __name__ == "__main__":
    sys.exit(main())
