#!/usr/bin/python3
"""A second, independent reader of the .vxl format, written from spec/vxl-format.md alone.

    /usr/bin/python3 scripts/vxl_spec_reader.py FILE.vxl [--compare SOURCE.tck] [-q]

It checks what spec §7 asks of `open` and of `verify` (header and section checksums, padding, counts,
voxel table, tight and META bounds, grid extent, levels, orders, the voxline walk, VXIX, SLEN) and
rebuilds every streamline's points from VXLN/STRM/VERT (§5.4, §5.6, §5.7). With --compare SOURCE (a TCK,
read by nibabel or, for what nibabel refuses such as Float64, by the built-in reader) it also rebuilds every
vertex the converter must have made from the source (§6.1, §6.3 face points, §5.4 packing) and checks the
file against them, and PROV's source record (§5.8) against the source file. (Other formats nibabel reads
are compared by points only, within one float32 spacing: nibabel maps TRK to RAS in float32, §8 in binary64.)

Exit status, for use as a test: 0 valid, 1 invalid, 2 usage error (bad arguments, unreadable file or
source). The last line printed is one line: "FILE: OK ..." or "FILE: INVALID: byte N: what was expected";
-q prints only that line. Writer rules that §7 does not ask a reader to enforce (+0 for a zero bound, the
section order and placement of §2, PROV's serialisation and converter keys, §5.10's VDIR recipe) are
reported as notes, not failures.

Deliberately no code from the C++ implementation: where the spec still leaves a choice, the comment says
"ASSUMED" and what was tried; everything else cites the section that states it.
"""
import argparse
import itertools
import json
import math
import os
import struct
import sys

import numpy as np
import xxhash

MAGIC = b"\x89VXL\r\n\x1a\n"
GOLDEN = 0x9E3779B97F4A7C15
# §4's table: known ids and whether each must carry the required flag (§7 step 2).
KNOWN = {b"META": 1, b"DIRS": 1, b"VDIR": 1, b"VOXT": 1, b"VERT": 1, b"ORDB": 1, b"ORDR": 1, b"VXLN": 1,
         b"STRM": 1, b"LODS": 1, b"VXIX": 0, b"SLEN": 0, b"PROV": 0, b"GRPS": 0, b"VVAL": 0, b"SVAL": 0,
         b"GDAT": 0}
# §2: the order the converter writes (informative: readers find sections by id and accept any order).
CONVERTER_ORDER = ["META", "DIRS", "VDIR", "VOXT", "LODS", "VERT", "ORDB", "VXLN", "STRM", "VXIX", "SLEN",
                   "PROV", "GRPS", "VVAL", "SVAL", "GDAT"]
VOXT_DT = np.dtype([("coord", "<i4", 3), ("flags", "<u4"), ("tmin", "<f4", 3), ("tmax", "<f4", 3),
                    ("vfirst", "<u8"), ("vcount", "<u4"), ("scount", "<u4"), ("ooff", "<u8")])  # §5.3
assert VOXT_DT.itemsize == 64


class Invalid(Exception):
    pass


class Usage(Exception):
    """Bad arguments or an unreadable source: exit status 2."""


def fail(offset, msg):
    raise Invalid(f"byte {offset}: {msg}")


def need(cond, offset, msg):
    if not cond:
        fail(offset, msg)


def align(x, a):
    return (x + a - 1) // a * a


def splitmix_mix(z):
    """The SplitMix64 output function on uint64 numpy arrays (wrapping arithmetic), §6.5."""
    with np.errstate(over="ignore"):
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        return z ^ (z >> np.uint64(31))


def depths(n, levels):
    """§6.5: depth(j) = min(Λ−1, ⌊tz(SplitMix64(j)) / 3⌋); all 0 without levels."""
    if levels < 2:
        return np.zeros(n, np.int64)
    with np.errstate(over="ignore"):
        z = splitmix_mix(np.arange(n, dtype=np.uint64) + np.uint64(GOLDEN))
    tz = np.full(n, 64, np.int64)
    nz = z != 0
    low = z[nz] & (~z[nz] + np.uint64(1))          # lowest set bit; its log2 is the trailing-zero count
    tz[nz] = np.round(np.log2(low.astype(np.float64))).astype(np.int64)
    return np.minimum(levels - 1, tz // 3)


def self_test_depths():
    # §6.5's test vectors (Λ = 8), so a wrong SplitMix64 cannot silently mis-walk a file with levels.
    d = depths(3000, 8)
    want = {0: 0, 5: 0, 7: 0, 28: 0, 6: 4, 29: 1, 33: 1, 38: 1, 43: 1, 149: 2, 155: 2, 160: 2, 209: 2,
            575: 3, 1625: 3, 2028: 3, 2565: 3}
    assert all(d[j] == v for j, v in want.items()), "SplitMix64 depth test vectors of §6.5 fail"


def pack_q(x, tmin, tmax):
    """§5.4, how a writer packs f32 coordinates x across f32 tight bounds: step in binary32, then
    t = (x − tight_min) / step in binary64 and q = ⌊t + 0.5⌋, 0 when t ≤ 0 or step = 0, 1023 when t ≥ 1023."""
    step = ((tmax - tmin) / np.float32(1023)).astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (x.astype(np.float64) - tmin.astype(np.float64)) / step
        q = np.floor(t + 0.5)                       # "halves rounded up; the addition in binary64"
    return np.where((t <= 0) | (step == 0), 0, np.where(t >= 1023, 1023, q)).astype(np.int64)


def read_bits(padded, bitpos, b):
    """Entries of b bits (b per entry) starting at absolute bit positions `bitpos` of a byte array
    (padded with 8 zero bytes), LSB first: bit t is bit t mod 8 of byte ⌊t/8⌋ (§5.5 ORDB; ORDR is the
    same with b = 8·w)."""
    byte = (bitpos >> np.uint64(3)).astype(np.int64)
    word = np.zeros(len(bitpos), np.uint64)
    for k in range(5):                            # b ≤ 32 plus a shift ≤ 7 needs at most 5 bytes
        word |= padded[byte + k].astype(np.uint64) << np.uint64(8 * k)
    mask = (np.uint64(1) << b.astype(np.uint64)) - np.uint64(1)
    return ((word >> (bitpos & np.uint64(7))) & mask).astype(np.int64)


class VxlFile:
    def __init__(self, path, log, data=None):
        self.path, self.log = path, log
        if data is None:
            with open(path, "rb") as f:
                data = f.read()
        self.data = data
        self.buf = np.frombuffer(self.data, np.uint8)
        self.notes = []                           # things that are not errors but worth reporting

    # ---------- §3 header, §4 section table, §2 layout, §7 steps 1–2 ----------
    def parse_container(self):
        d = self.data
        need(len(d) >= 64, 0, f"file of {len(d)} bytes is shorter than the 64-byte header")
        need(d[:8] == MAGIC, 0, f"magic {d[:8].hex()} != {MAGIC.hex()}")
        (self.major, self.minor, hsize, fsize, tab_off, count, flags, hsum) = struct.unpack_from(
            "<HHIQQIIQ", d, 8)
        need(self.major in (1, 2), 8, f"version_major {self.major}, expected 1 or 2")
        need(hsize == 64, 12, f"header_size {hsize}, expected 64")
        need(fsize == len(d), 16, f"file_size {fsize} but the file has {len(d)} bytes")
        need(fsize % 64 == 0, 16, f"file_size {fsize} is not a multiple of 64 (§2)")
        need(tab_off == 64, 24, f"section_table_offset {tab_off}, expected 64")
        need(count <= 64, 32, f"section_count {count} > 64")
        need(flags == 0, 36, f"header flags {flags:#x}, expected 0")
        need(d[48:64] == bytes(16), 48, "header reserved bytes not zero")
        tab_end = 64 + 32 * count
        need(tab_end <= fsize, 24, "section table runs past the end of the file")
        # §3: checksum of the header with the checksum field zeroed, then the whole table.
        h = xxhash.xxh3_64(d[:40] + bytes(8) + d[48:64] + d[64:tab_end]).intdigest()
        need(h == hsum, 40, f"header_checksum {hsum:#018x}, computed {h:#018x}")
        self.sections, prev_end = {}, tab_end
        for i in range(count):
            e = 64 + 32 * i
            sid, sflags, off, size, csum = struct.unpack_from("<4sIQQQ", d, e)
            need(all(0x20 <= c <= 0x7E for c in sid), e, f"section id {sid!r} is not printable ASCII")
            need(sid.decode() not in self.sections, e, f"section {sid.decode()} appears twice")
            need(sflags & ~1 == 0, e + 4, f"{sid.decode()}: flags {sflags:#x} has bits other than 0")
            need(off % 64 == 0, e + 8, f"{sid.decode()}: offset {off} not a multiple of 64")
            need(off >= tab_end, e + 8, f"{sid.decode()}: offset {off} inside header/table (< {tab_end})")
            need(off <= fsize and size <= fsize - off, e + 16, f"{sid.decode()}: payload past end of file")
            # §2: non-decreasing offsets, no overlap; a size-0 section takes no bytes, so the next may
            # share its offset (a file of no points has several)
            need(off >= prev_end, e + 8, f"{sid.decode()}: offset {off} overlaps or precedes the "
                 f"previous section (ends at {prev_end})")
            if sid in KNOWN:
                need(bool(sflags & 1) == bool(KNOWN[sid]), e + 4, f"{sid.decode()}: required flag "
                     f"{sflags & 1}, §4/§7 step 2 expect {KNOWN[sid]}")
            else:
                need(not sflags & 1, e, f"unknown required section {sid.decode()} (§10)")
                self.notes.append(f"unknown optional section {sid.decode()} ignored")
            # §2/§7: every byte between payloads is zero padding
            gap = d[prev_end:off]
            need(gap.count(0) == len(gap), prev_end, f"padding before {sid.decode()} not zero")
            if off != align(prev_end, 64):      # §2 writer rule, not an open/verify check (§7)
                self.notes.append(f"{sid.decode()} does not start at the first 64-byte boundary")
            h = xxhash.xxh3_64(d[off:off + size]).intdigest()
            need(h == csum, e + 24, f"{sid.decode()}: checksum {csum:#018x}, computed {h:#018x} over "
                 f"bytes {off}..{off + size}")
            self.sections[sid.decode()] = (off, size, e)
            prev_end = off + size
        ids = [k for k in self.sections if k in CONVERTER_ORDER]
        if ids != sorted(ids, key=CONVERTER_ORDER.index):
            self.notes.append(f"section order {' '.join(self.sections)} is not the converter's (§2)")
        tail = d[prev_end:]
        need(tail.count(0) == len(tail), prev_end, "padding after the last section not zero")
        need(fsize == align(prev_end, 64), 16, f"file_size {fsize}, §2: ends at the last section's "
             f"padding ({align(prev_end, 64)})")

    def sec(self, name):
        off, size, _ = self.sections[name]
        return off, size

    def sec_array(self, name, dtype, count):
        """The section as `count` items of dtype; its size must be exactly that (§7 step 3)."""
        off, size = self.sec(name)
        want = count * np.dtype(dtype).itemsize
        need(size == want, self.sections[name][2] + 16, f"{name}: size {size}, expected {want}")
        return np.frombuffer(self.data, dtype, count, off)

    # ---------- §5.1 META and §7 step 3 ----------
    def parse_meta(self):
        for s in ("META", "DIRS", "VOXT", "VERT", "VXLN", "STRM"):
            need(s in self.sections, 64, f"required section {s} missing")
        need(("ORDB" in self.sections) != ("ORDR" in self.sections), 64,
             "exactly one of ORDB / ORDR required (§4)")
        off, size = self.sec("META")
        need(size == 256, self.sections["META"][2] + 16, f"META size {size}, expected 256")
        f = struct.unpack_from("<6QIId3d3iI3d3dII", self.data, off)
        (self.N, self.P, self.V, self.S, self.L, self.synth, self.nvox, self.K, self.s) = f[:9]
        self.origin, self.dims = np.array(f[9:12]), np.array(f[12:15])
        self.order_set, self.bmin, self.bmax = f[15], np.array(f[16:19]), np.array(f[19:22])
        self.pos_enc, lc = f[22], f[23]
        need(self.data[off + 160:off + 256] == bytes(96), off + 160, "META reserved bytes not zero")
        need(self.pos_enc in (0, 1), off + 152, f"position_encoding {self.pos_enc}, expected 0 or 1")
        need(not (self.pos_enc == 1 and self.major == 1), off + 152, "packed positions in a 1.x file")
        need(1 <= self.K <= 64, off + 52, f"stored_order_count {self.K}, expected 1..64")
        need(self.order_set in (0, 1, 2), off + 100, f"order_set {self.order_set}, expected 0..2")
        need(self.order_set != 0 or self.K == 3, off + 52, "order_set axis needs K = 3")
        need(self.order_set != 1 or self.K == 7, off + 52, "order_set axis+diag needs K = 7")
        need(math.isfinite(self.s) and self.s > 0, off + 56, f"voxel_size {self.s} not finite > 0")
        need(self.nvox <= 2**31 - 1, off + 48, "voxel_count ≥ 2^31")
        need(self.P + self.synth <= self.V, off + 8, "P + synthetic_point_count > V (§7 step 3)")
        need(("VDIR" in self.sections) == (self.order_set == 2), off + 100,
             "VDIR must be present exactly when order_set = 2 (§5.10)")
        need(lc == 0 or 2 <= lc <= 8, off + 156, f"level_count {lc}, expected 0 or 2..8")
        need(("LODS" in self.sections) == (lc >= 2), off + 156, "LODS present iff level_count ≥ 2")
        need(lc == 0 or (self.major, self.minor) >= (2, 1), 8, "levels need version ≥ 2.1")
        self.levels = max(lc, 1)                 # number of levels actually stored, level 0 included
        self.lc = lc
        if self.P == 0:
            # §5.1; .any() compares numerically, so −0 passes (readers compare as numbers, §5.1 "Zeros")
            need(not self.origin.any() and not self.bmin.any() and not self.bmax.any()
                 and not self.dims.any() and self.nvox == 0, off, "P = 0 needs zero grid/bounds (§5.1)")
            need(lc == 0, off + 156, f"level_count {lc} with P = 0, §5.1 needs 0")
        # §5.1 "Zeros": +0 is a writer rule; older converters may have written −0, so only a note
        z = np.r_[self.origin, self.bmin, self.bmax]
        if (np.signbit(z) & (z == 0)).any():
            self.notes.append("META holds a −0 origin/bound (writers store +0, §5.1; accepted)")
        self.check_version()

    def check_version(self):
        """§3: the header's version must be the lowest that holds what the file has (§10)."""
        has = self.sections.__contains__
        major = 2 if (self.pos_enc == 1 or self.lc >= 2) else 1
        if has("SLEN"):
            minor = 4 if major == 2 else 5
        elif has("ORDB"):
            minor = 3 if major == 2 else 4
        elif major == 2:
            minor = 2 if has("GDAT") else 1 if has("LODS") else 0
        else:
            minor = 3 if has("GDAT") else 2 if (has("VVAL") or has("SVAL")) else 1 if has("VDIR") else 0
        need((self.major, self.minor) == (major, minor), 8,
             f"version {self.major}.{self.minor}, §3 gives {major}.{minor} for these sections")

    # ---------- §5.2 DIRS, §5.10 VDIR ----------
    def parse_dirs(self):
        dt = np.dtype([("v", "<f4", 3), ("r", "<u4")])
        dirs = self.sec_array("DIRS", dt, self.K)
        off = self.sec("DIRS")[0]
        need(not dirs["r"].any(), off, "DIRS reserved field not zero")
        self.check_unit(dirs["v"], off, "DIRS")
        # §5.2: the axis set exactly; axis+diag adds (c,c,c), (−c,c,c), (c,−c,c), (c,c,−c), c = f32(1/√3)
        want = np.eye(3, dtype=np.float32)
        if self.order_set == 1:
            c = np.float32(1 / math.sqrt(3))                # bits 0x3F13CD3A, as §5.2 gives
            want = np.r_[want, np.float32([[c, c, c], [-c, c, c], [c, -c, c], [c, c, -c]])]
        if self.order_set in (0, 1):
            need((dirs["v"] == want).all(), off, f"DIRS of order_set {self.order_set} are not §5.2's set")
        if self.order_set == 2:
            need((dirs["v"] == np.float32([1, 0, 0])).all(), off, "random: DIRS must hold K × (1,0,0)")
            vd = self.sec_array("VDIR", dt, self.nvox * self.K)
            need(not vd["r"].any(), self.sec("VDIR")[0], "VDIR reserved field not zero")
            self.check_unit(vd["v"], self.sec("VDIR")[0], "VDIR")
            self.vdir = vd["v"].astype(np.float64).reshape(self.nvox, self.K, 3)
        self.dirs = dirs["v"].astype(np.float64)

    def check_vdir_recipe(self):
        """§5.10's recipe for `--orders random:N` (informative: readers sort by the stored vectors, so a
        difference is a note). Vectorised over voxels; rejection sampling redraws only the rejected."""
        state = np.full(self.nvox, 0x566F786C696E6573, np.uint64)
        def nxt(st, sel=slice(None)):
            with np.errstate(over="ignore"):
                st[sel] = st[sel] + np.uint64(GOLDEN)       # §5.10: the sum is the new state ...
            return splitmix_mix(st[sel])                    # ... and its SplitMix64 mix the output
        coord = self.vt["coord"].astype(np.int64)
        for c in range(3):
            state ^= (coord[:, c] & 0xFFFFFFFF).astype(np.uint64) << np.uint64(16 * c)
            state = nxt(state)                              # "replaced by the next output"
        out = np.zeros((self.nvox, self.K, 3), np.float32)
        unif = lambda w: (w >> np.uint64(11)).astype(np.float64) * 2.0**-52 - 1
        for k in range(self.K):
            todo = np.arange(self.nvox)
            while len(todo):
                x, y, z = (unif(nxt(state, todo)) for _ in range(3))   # drawn x, then y, then z
                r2 = (x * x + y * y) + z * z
                ok = (r2 >= 1e-6) & (r2 <= 1)
                inv = 1 / np.sqrt(r2[ok])
                out[todo[ok], k] = np.c_[x[ok] * inv, y[ok] * inv, z[ok] * inv].astype(np.float32)
                todo = todo[~ok]
        stored = self.vdir.astype(np.float32)
        same = (out.view(np.uint32) == stored.view(np.uint32)).all(2)
        if not same.all():
            i = np.argwhere(~same)[0]
            self.notes.append(f"VDIR differs from §5.10's recipe in {int((~same).sum())} of {same.size} "
                              f"directions (first: voxel {i[0]} k {i[1]}: {stored[i[0], i[1]]} vs {out[i[0], i[1]]})")
        return bool(same.all())

    def check_unit(self, v, off, name):
        ln = np.sqrt((v.astype(np.float64) ** 2).sum(1))
        bad = np.nonzero(np.abs(ln - 1) > 1e-5)[0]
        need(len(bad) == 0, off + 16 * (bad[0] if len(bad) else 0), f"{name} vector not of unit length")

    # ---------- §5.3 VOXT, §5.12 LODS, §7 steps 4–5 ----------
    def parse_voxels(self):
        vt = self.sec_array("VOXT", VOXT_DT, self.nvox)
        self.vt, base = vt, self.sec("VOXT")[0]
        at = lambda i, fo: base + 64 * int(i) + fo      # byte offset of voxel i's field, for messages
        def bad(mask, fo, msg):
            idx = np.nonzero(mask)[0]
            need(len(idx) == 0, at(idx[0] if len(idx) else 0, fo),
                 f"voxel {idx[0] if len(idx) else 0}: {msg}")
        c = vt["coord"].astype(np.int64)
        bad(((c < 0) | (c >= self.dims)).any(1), 0, "coord outside grid_dims")
        a, b = c[:-1, ::-1], c[1:, ::-1]                           # (z, y, x) order, §5.3
        first_diff = np.argmax(a != b, axis=1)                     # lexicographic: first differing axis
        r = np.arange(len(a))
        bad(np.r_[False, ~((a != b).any(1) & (a[r, first_diff] < b[r, first_diff]))], 0,
            "coords not strictly increasing in (z, y, x)")
        vc, sc = vt["vcount"].astype(np.int64), vt["scount"].astype(np.int64)
        bad(vc < 1, 48, "vertex_count < 1")
        bad(sc >= vc, 52, "segment_count ≥ vertex_count")
        first = np.r_[0, np.cumsum(vc)[:-1]] if self.nvox else np.zeros(0, np.int64)
        bad(vt["vfirst"].astype(np.int64) != first, 40, "vertex blocks not contiguous from 0")
        need(vc.sum() == self.V, base, f"vertex counts sum to {vc.sum()}, META says V = {self.V}")
        need(sc.sum() == self.S, base, f"segment counts sum to {sc.sum()}, META says S = {self.S}")
        code = np.where(vc <= 65536, 0, np.where(vc <= 2**24, 1, 2))
        bad(vt["flags"] != code, 12, "flags are not the width code of vertex_count (§5.3)")
        tmin, tmax = vt["tmin"].astype(np.float64), vt["tmax"].astype(np.float64)
        bad(~(np.isfinite(tmin) & np.isfinite(tmax)).all(1), 16, "tight bounds not finite")
        bad((tmin > tmax).any(1), 16, "tight_min > tight_max")
        bad(~np.isfinite(vt["tmax"] - vt["tmin"]).all(1), 16, "tight extent not finite in binary32")
        bad(((tmin < self.bmin - self.s) | (tmax > self.bmax + self.s)).any(1), 16,
            "tight bounds outside [bounds_min − s, bounds_max + s]")
        lo = self.origin + c * self.s - 1.5 * self.s
        hi = self.origin + (c + 1) * self.s + 1.5 * self.s
        bad(((tmin < lo) | (tmax > hi)).any(1), 16, "tight bounds outside the cell widened by 1.5·s")
        # §5.3 "a zero is written as +0" is a writer rule; like META's (§5.1 "Zeros") compared as numbers
        negz = ((np.signbit(vt["tmin"]) & (vt["tmin"] == 0)) | (np.signbit(vt["tmax"]) & (vt["tmax"] == 0))).any(1)
        if negz.any():
            self.notes.append(f"{int(negz.sum())} voxel(s) hold a −0 tight bound (writers store +0, §5.3; accepted)")
        # §7 step 5
        mo = self.sec("META")[0]
        if self.P:
            need((self.bmin <= self.bmax).all(), mo + 104, "bounds_min > bounds_max")
            need((np.abs(self.origin - self.bmin) <= self.s).all(), mo + 64, "|grid_origin − bounds_min| > s")
            g = np.floor((self.bmax - self.bmin) / self.s) + 1
            need((np.abs(self.dims - g) <= 1).all(), mo + 88, f"grid_dims {self.dims} not within 1 of {g}")
            if not (self.origin == self.bmin).all():     # §5.1: "= grid_origin in a converted file"
                self.notes.append(f"bounds_min {self.bmin} != grid_origin {self.origin} (a converted file has them equal)")
            # §6.1: grid_dims = v(max point) + 1, the same formula as the voxel of a point
            g61 = np.floor((self.bmax - self.origin) / self.s) + 1
            if not (self.dims == g61).all():
                self.notes.append(f"grid_dims {self.dims} != floor((bounds_max−o)/s)+1 = {g61}")
            # §7 verify: bounds_min/max are the extremes of the tight bounds (numerically, §5.1)
            need((tmin.min(0) == self.bmin).all(), mo + 104,
                 f"bounds_min {self.bmin} != the smallest tight_min {tmin.min(0)} (§5.1, §7)")
            need((tmax.max(0) == self.bmax).all(), mo + 128,
                 f"bounds_max {self.bmax} != the largest tight_max {tmax.max(0)} (§5.1, §7)")
            # §7 verify: on every axis the voxel coordinates run from 0 to grid_dims − 1 (§6.1)
            need((c.min(0) == 0).all() and (c.max(0) == self.dims - 1).all(), mo + 88,
                 f"voxel coordinates run from {c.min(0)} to {c.max(0)}, §7 needs 0 to grid_dims − 1 = {self.dims - 1}")
        # §5.12 LODS: v[i, d] for d = 0 .. levels (with v[i, levels] = 0), n[i, d] likewise
        self.vlev = np.zeros((self.nvox, self.levels + 1), np.int64)
        self.nlev = np.zeros((self.nvox, self.levels + 1), np.int64)
        self.vlev[:, 0], self.nlev[:, 0] = vc, sc
        if self.lc >= 2:
            lods = self.sec_array("LODS", "<u4", self.nvox * (self.lc - 1) * 2).astype(np.int64)
            lods = lods.reshape(self.nvox, self.lc - 1, 2)
            self.vlev[:, 1:self.lc], self.nlev[:, 1:self.lc] = lods[:, :, 0], lods[:, :, 1]
            lb = self.sec("LODS")[0]
            for d in range(1, self.lc):
                v, n = self.vlev[:, d], self.nlev[:, d]
                idx = np.nonzero((v > self.vlev[:, d - 1]) | (n > self.nlev[:, d - 1]) |
                                 ~((n < v) | ((n == 0) & (v == 0))))[0]
                need(len(idx) == 0, lb + 8 * ((idx[0] if len(idx) else 0) * (self.lc - 1) + d - 1),
                     f"LODS voxel {idx[0] if len(idx) else 0} level {d} breaks §5.12's rules")
        # §5.5: per voxel, level sizes in bytes and the implied end of its orders
        ordname = "ORDB" if "ORDB" in self.sections else "ORDR"
        self.ordname, (self.ord_off, ord_size) = ordname, self.sec(ordname)
        if ordname == "ORDB":
            # b = bit width of v − 1, at least 1 (§5.5; for n = 0 it does not matter). frexp's exponent
            # is the exact bit width of an integer (log2 of floats could round near powers of two)
            self.bits = np.maximum(1, np.frexp((self.vlev - 1).astype(np.float64))[1]).astype(np.int64)
        else:
            self.bits = 8 * np.where(self.vlev <= 65536, 2, np.where(self.vlev <= 2**24, 3, 4))
        arr_bytes = (self.nlev * self.bits + 7) // 8
        lvl_bytes = (self.K * arr_bytes[:, :self.levels] + 3) // 4 * 4     # pad4 of each level
        self.lvl_start = np.c_[np.zeros(self.nvox, np.int64), np.cumsum(lvl_bytes, 1)]
        ooff = vt["ooff"].astype(np.int64)
        bad(ooff % 4 != 0, 56, "order_offset not a multiple of 4")
        end = ooff + self.lvl_start[:, -1]
        bad(end > ord_size, 56, f"orders run past the end of {ordname}")
        prev_end = np.r_[0, end[:-1]]
        bad(ooff < prev_end, 56, "order_offset before the previous voxel's end")
        # §5.3: order_offset is into ORDB (or ORDR); §5.5: every voxel's K arrays (each level's, with
        # levels) are padded to 4 bytes, and "the next voxel's order_offset follows ... directly"
        bad(ooff != prev_end, 56, "order_offset does not follow the previous voxel's orders directly")
        if self.nvox and end[-1] != ord_size:
            self.notes.append(f"{ordname} size {ord_size} != end of last voxel's orders {end[-1]}")

    # ---------- §5.4 VERT ----------
    def decode_vertices(self):
        vox_of = np.repeat(np.arange(self.nvox), self.vt["vcount"].astype(np.int64))
        self.vox_of = vox_of
        tmin, tmax = self.vt["tmin"].astype(np.float64), self.vt["tmax"].astype(np.float64)
        # §5.4 error bound B per voxel and axis (double; it is a bound, not a bit pattern)
        self.B = (tmax - tmin) * (1 / 2046 + 2.0**-21) + 2.0**-23 * np.maximum(np.abs(tmin), np.abs(tmax))
        if self.pos_enc == 0:
            self.pos = self.sec_array("VERT", "<f4", self.V * 3).reshape(-1, 3)
            self.endbit = None
            # §7 verify (float32): every vertex within the tight bounds and each bound reached, i.e. the
            # bounds are the vertices' extremes, compared as numbers (−0 = +0)
            lo = np.full((self.nvox, 3), np.inf, np.float32)
            hi = np.full((self.nvox, 3), -np.inf, np.float32)
            np.minimum.at(lo, vox_of, self.pos)
            np.maximum.at(hi, vox_of, self.pos)
            i = np.nonzero((lo != self.vt["tmin"]).any(1) | (hi != self.vt["tmax"]).any(1))[0]
            need(len(i) == 0, self.sec("VOXT")[0] + 64 * (i[0] if len(i) else 0) + 16,
                 f"voxel {i[0] if len(i) else 0}: tight bounds are not its vertices' extremes (§5.3)")
            return
        w = self.sec_array("VERT", "<u4", self.V)
        idx = np.nonzero(w >> np.uint32(31))[0]
        need(len(idx) == 0, self.sec("VERT")[0] + 4 * (idx[0] if len(idx) else 0), "packed word bit 31 set")
        q = np.stack([(w >> np.uint32(10 * c)) & np.uint32(1023) for c in range(3)], 1).astype(np.float32)
        lo, hi = self.vt["tmin"][vox_of], self.vt["tmax"][vox_of]
        step = (hi - lo) / np.float32(1023)        # binary32, each operation rounded, no FMA (§5.4)
        self.pos = lo + q * step
        self.endbit = (w >> np.uint32(30)) & np.uint32(1) == 1
        # §7 verify (packed): on every axis the words reach the quanta that tight_min (0) and tight_max
        # pack to (§5.4: 1023 unless step underflows); pack_q is monotone, so min and max suffice
        self.q = q.astype(np.int64)
        qmin = np.full((self.nvox, 3), 1023)
        qmax = np.zeros((self.nvox, 3), np.int64)
        np.minimum.at(qmin, vox_of, self.q)
        np.maximum.at(qmax, vox_of, self.q)
        tlo, thi = self.vt["tmin"], self.vt["tmax"]
        i = np.nonzero(((qmin != pack_q(tlo, tlo, thi)) | (qmax != pack_q(thi, tlo, thi))).any(1))[0]
        need(len(i) == 0, self.sec("VOXT")[0] + 64 * (i[0] if len(i) else 0) + 16,
             f"voxel {i[0] if len(i) else 0}: packed words span q {qmin[i[0]] if len(i) else 0} … "
             f"{qmax[i[0]] if len(i) else 0}, its tight bounds pack to 0 … "
             f"{pack_q(thi, tlo, thi)[i[0]] if len(i) else 0} (§5.4, §7)")

    # ---------- §5.6 VXLN, §5.7 STRM, §6.2/6.3 walk ----------
    def walk(self):
        strm = self.sec_array("STRM", "<u8", self.N + 1).astype(np.int64)
        so = self.sec("STRM")[0]
        need(strm[0] == 0 and strm[-1] == self.L, so, f"STRM must run from 0 to L = {self.L}")
        idx = np.nonzero(np.diff(strm) < 0)[0]
        need(len(idx) == 0, so + 8 * (idx[0] + 1 if len(idx) else 0), "STRM decreases")
        vx = self.sec_array("VXLN", "<u4", self.L * 2).reshape(-1, 2)
        xo = self.sec("VXLN")[0]
        voxel, m = vx[:, 0].astype(np.int64), (vx[:, 1] & 0x7FFFFFFF).astype(np.int64)
        syn = (vx[:, 1] >> 31).astype(bool)
        i = np.nonzero((voxel >= self.nvox) | (m < 1))[0]
        need(len(i) == 0, xo + 8 * (i[0] if len(i) else 0), "VXLN entry: voxel out of range or m = 0")
        sid = np.repeat(np.arange(self.N), np.diff(strm))       # streamline of each voxline
        last = np.zeros(self.L, bool)
        last[strm[1:][np.diff(strm) > 0] - 1] = True           # last voxline of its streamline
        firstv = np.zeros(self.L, bool)
        firstv[strm[:-1][np.diff(strm) > 0]] = True
        size = m + (~last)                                      # own points + connecting vertex
        dep = depths(self.N, self.lc)[sid]
        # §5.6: one cursor per (voxel, depth); depth δ's part is [v_{δ+1}, v_δ) of the block, deepest first
        grp = voxel * self.levels + dep
        order = np.lexsort((np.arange(self.L), grp))            # stable: VXLN order within a group
        ssz = size[order]
        excl = np.cumsum(ssz) - ssz
        gs = grp[order]
        newg = np.r_[True, gs[1:] != gs[:-1]] if self.L else np.zeros(0, bool)
        gfirst = np.maximum.accumulate(np.where(newg, np.arange(self.L), 0)) if self.L else newg
        start = np.empty(self.L, np.int64)
        vfirst = self.vt["vfirst"].astype(np.int64)
        start[order] = vfirst[voxel[order]] + self.vlev[voxel[order], dep[order] + 1] + excl - excl[gfirst]
        used = np.bincount(grp, weights=size, minlength=self.nvox * self.levels).reshape(self.nvox, self.levels)
        want = self.vlev[:, :-1] - self.vlev[:, 1:]
        bv = np.nonzero((used != want).any(1))[0]
        need(len(bv) == 0, self.sec("VOXT")[0] + 64 * (bv[0] if len(bv) else 0),
             f"voxline walk does not consume voxel {bv[0] if len(bv) else 0}'s block exactly (§5.6)")
        # voxline ends: the last vertex of each voxline (§5.4 bit 30, §6.2)
        end = np.zeros(self.V, bool)
        end[start + size - 1] = True
        if self.endbit is not None:
            i = np.nonzero(end != self.endbit)[0]
            need(len(i) == 0, self.sec("VERT")[0] + 4 * (i[0] if len(i) else 0),
                 f"vertex {i[0] if len(i) else 0}: bit 30 is {int(self.endbit[i[0]]) if len(i) else 0}, "
                 "the walk says otherwise")
        # segments per voxel = vertices that do not end a voxline (§6.2)
        nseg = self.vt["vcount"].astype(np.int64) - np.bincount(voxel, minlength=self.nvox)
        bv = np.nonzero(nseg != self.vt["scount"])[0]
        need(len(bv) == 0, self.sec("VOXT")[0] + 64 * (bv[0] if len(bv) else 0) + 52,
             "segment_count != vertices that do not end a voxline")
        # connecting vertex = next voxline's first point: bit for bit (float32), within both B (packed)
        nl = np.nonzero(~last)[0]
        a, b = self.pos[start[nl] + m[nl]], self.pos[start[nl + 1]]
        if self.pos_enc == 0:
            i = np.nonzero((a.view(np.uint32) != b.view(np.uint32)).any(1))[0]
        else:
            tol = self.B[voxel[nl]] + self.B[voxel[nl + 1]]
            i = np.nonzero((np.abs(a.astype(np.float64) - b) > tol).any(1))[0]
        need(len(i) == 0, xo + 8 * (nl[i[0]] if len(i) else 0),
             f"voxline {nl[i[0]] if len(i) else 0}: connecting vertex != next voxline's first point")
        # §6.2/§6.3: consecutive voxlines of a streamline are in different voxels, neighbours unless the
        # next starts with a face point (§6.3 crosses faces at the same t at once, ±1 per face, so two
        # faces of one axis at one t, possible only with planes that round together, move it by 2)
        c = self.vt["coord"].astype(np.int64)
        dv = np.abs(c[voxel[nl]] - c[voxel[nl + 1]]).max(1) if len(nl) else np.zeros(0)
        i = np.nonzero((dv == 0) | ((dv > 1) & ~syn[nl + 1]))[0]
        need(len(i) == 0, xo + 8 * (nl[i[0]] if len(i) else 0),
             "consecutive voxlines in the same voxel, or a long step (§6.3) not split at the faces")
        # by §6.3's construction a synthetic point follows a crossing, so it never starts a streamline
        i = np.nonzero(syn & firstv)[0]
        need(len(i) == 0, xo + 8 * (i[0] if len(i) else 0), "a streamline's first point is marked synthetic")
        # own points, synthetic first points dropped (§6.3: "export drops them")
        need(int(syn.sum()) == self.synth, self.sec("META")[0] + 40,
             f"{int(syn.sum())} synthetic voxlines, META says {self.synth}")
        own = m - syn
        need(int(own.sum()) == self.P, self.sec("META")[0] + 8, f"points add up to {own.sum()}, META says P = {self.P}")
        cs = np.cumsum(own) - own
        pidx = np.repeat(start + syn, own) + (np.arange(int(own.sum())) - np.repeat(cs, own))
        self.points = self.pos[pidx]
        self.point_vox = voxel[np.repeat(np.arange(self.L), own)]
        self.counts = np.bincount(sid, weights=own, minlength=self.N).astype(np.int64)
        self.voxel, self.start, self.m, self.syn, self.sid, self.last, self.firstv = \
            voxel, start, m, syn, sid, last, firstv
        self.end, self.pidx, self.own = end, pidx, own

    def check_converted_point_voxels(self, prov):
        """§6.1 voxel of each point, where the file alone determines it: float32 positions (packed ones are checked
        in compare) of a converted file. A file unpacked from a package (PROV has "vxlz") keeps the package's
        voxels with quantised positions, which may lie up to the package's bound outside them (§8)."""
        if self.pos_enc != 0:
            return
        if isinstance(prov, dict) and "vxlz" in prov:
            self.notes.append("unpacked from a package: its points' voxels are the package's (§8), not checked")
        else:
            self.check_point_voxels(self.points)

    def check_point_voxels(self, pts):
        v = np.floor((pts.astype(np.float64) - self.origin) / self.s).astype(np.int64)
        i = np.nonzero((v != self.vt["coord"][self.point_vox]).any(1))[0]
        need(len(i) == 0, self.sec("VXLN")[0], f"point {i[0] if len(i) else 0}: §6.1 puts it in voxel "
             f"{v[i[0]] if len(i) else ''}, the file in {self.vt['coord'][self.point_vox[i[0]]] if len(i) else ''}")

    # ---------- §5.5 orders, §6.4 keys, §5.12 levels ----------
    def check_orders(self):
        """Every level's K arrays of every voxel, vectorised over voxels (one pass per level and k)."""
        size = self.sec(self.ordname)[1]
        buf = self.buf[self.ord_off:self.ord_off + size]
        padded = np.r_[buf, np.zeros(8, np.uint8)]
        vfirst = self.vt["vfirst"].astype(np.int64)
        ooff = self.vt["ooff"].astype(np.int64)
        covered = np.zeros(size + 1, np.int64)          # difference array of bytes that hold entries
        # segment g (global vertex index) joins vertex g and g+1: double(a) + double(b), §6.4
        p = self.pos.astype(np.float64)
        ssum = p[:-1] + p[1:]
        self.ties, level0 = 0, {}
        for d in range(self.levels):
            n, v, b = self.nlev[:, d], self.vlev[:, d], self.bits[:, d]
            # the segments of level d: vertices of the prefix v_d that do not end a voxline (§5.12)
            local = np.arange(self.V) - vfirst[self.vox_of]
            want = ~self.end & (local < v[self.vox_of])
            cnt = np.bincount(self.vox_of[want], minlength=self.nvox)
            i = np.nonzero(cnt != n)[0]
            need(len(i) == 0, self.sec("VOXT")[0] + 64 * (i[0] if len(i) else 0) + 52,
                 f"voxel {i[0] if len(i) else 0} level {d}: {cnt[i[0]] if len(i) else 0} segments in its prefix, "
                 f"the table says {n[i[0]] if len(i) else 0}")
            nb = (n * b + 7) // 8                           # bytes of one array
            vox = np.repeat(np.arange(self.nvox), n)        # voxel of each entry
            j = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
            for k in range(self.K):
                start = ooff + self.lvl_start[:, d] + k * nb  # byte of array k of level d, per voxel
                np.add.at(covered, start, 1)
                np.add.at(covered, start + nb, -1)
                o = read_bits(padded, (8 * start[vox] + j * b[vox]).astype(np.uint64), b[vox])
                at = lambda e: self.ord_off + int(start[vox[e]]) + int(j[e]) * int(b[vox[e]]) // 8
                where = lambda e: f"voxel {vox[e]} level {d} order {k} entry {j[e]}"
                e = np.nonzero(o + 1 >= v[vox])[0]
                need(len(e) == 0, at(e[0]) if len(e) else 0,
                     f"{where(e[0]) if len(e) else ''}: entry {o[e[0]] if len(e) else 0}, §5.5 needs e + 1 < {v[vox[e[0]]] if len(e) else 0}")
                # permutation: every segment of the level exactly once (entries are in range, so a
                # count per global vertex cannot leak into another voxel)
                g = vfirst[vox] + o
                hit = np.bincount(g, minlength=self.V)
                e = np.nonzero(hit != want)[0]
                need(len(e) == 0, self.ord_off + int(ooff[self.vox_of[e[0]]]) if len(e) else 0,
                     f"voxel {self.vox_of[e[0]] if len(e) else 0} level {d} order {k} is not a permutation of "
                     "its segments (§5.5)")
                # §6.4: ascending key for the voxel's direction, equal keys by ascending index
                dv = self.vdir[vox, k] if self.order_set == 2 else np.broadcast_to(self.dirs[k], (len(g), 3))
                sg = ssum[g]
                # §6.4: ((s_x·d_x + s_y·d_y) + s_z·d_z) in binary64, each operation rounded (numpy does
                # not fuse); −0 and +0 compare equal, as §6.4 asks
                kk = (sg[:, 0] * dv[:, 0] + sg[:, 1] * dv[:, 1]) + sg[:, 2] * dv[:, 2]
                same = vox[1:] == vox[:-1]
                eq = kk[1:] == kk[:-1]
                bad = same & ~((kk[1:] > kk[:-1]) | (eq & (o[1:] > o[:-1])))
                e = np.nonzero(bad)[0]
                need(len(e) == 0, at(e[0]) if len(e) else 0,
                     f"{where(e[0]) if len(e) else ''}: not in ascending §6.4 key order")
                self.ties += int((same & eq).sum())
                # §5.12: level d's order is level 0's with the other segments left out
                if d == 0:
                    level0[k] = (vox, o)
                else:
                    v0, o0 = level0[k]
                    keep = o0 + 1 < v[v0]
                    need(np.array_equal(o0[keep], o), self.ord_off,
                         f"level {d} order {k} is not level 0's with the other segments left out (§5.12)")
                # "the bits after its last entry are zero" (§5.5, checked by verify §7)
                tail = (n * b) % 8
                lastb = padded[np.clip(start + nb - 1, 0, size)]    # (clipped: a section of size 0)
                e = np.nonzero((tail > 0) & (lastb >> tail > 0))[0]
                need(len(e) == 0, self.ord_off + int(start[e[0]] + nb[e[0]] - 1) if len(e) else 0,
                     f"voxel {e[0] if len(e) else 0} level {d} order {k}: bits after the last entry not zero")
        # everything else in the section (level padding to 4 bytes, §5.5) is zero
        used = np.cumsum(covered)[:-1] > 0
        e = np.nonzero(~used & (buf != 0))[0]
        need(len(e) == 0, self.ord_off + (e[0] if len(e) else 0), f"{self.ordname}: padding byte not zero")

    # ---------- §5.14 VXIX, §5.15 SLEN, §5.8 PROV, optional sections ----------
    def check_vxix(self):
        if "VXIX" not in self.sections:
            return
        off, size = self.sec("VXIX")
        need(self.N <= 2**29, off, "VXIX with N > 2^29")
        need(size == (self.nvox + 1) * 8 + self.L * 4, self.sections["VXIX"][2] + 16, "VXIX size")
        first = np.frombuffer(self.data, "<u8", self.nvox + 1, off).astype(np.int64)
        ent = np.frombuffer(self.data, "<u4", self.L, off + 8 * (self.nvox + 1))
        order = np.argsort(self.voxel, kind="stable")             # counting sort by voxel, §5.14
        want_first = np.r_[0, np.cumsum(np.bincount(self.voxel, minlength=self.nvox))]
        need(np.array_equal(first, want_first), off, "VXIX first[] differs from lists built from VXLN")
        want = (self.sid[order].astype(np.uint64) | (self.syn[order].astype(np.uint64) << np.uint64(29)) |
                (self.firstv[order].astype(np.uint64) << np.uint64(30)) |
                (self.last[order].astype(np.uint64) << np.uint64(31))).astype(np.uint32)
        i = np.nonzero(ent != want)[0]
        need(len(i) == 0, off + 8 * (self.nvox + 1) + 4 * (i[0] if len(i) else 0),
             f"VXIX entry {i[0] if len(i) else 0}: {ent[i[0]] if len(i) else 0:#x}, expected "
             f"{want[i[0]] if len(i) else 0:#x}")

    def lengths(self, pts, counts):
        """§5.15: per streamline, in double, sequential sum from +0 of sqrt((dx²+dy²)+dz²), then to f32."""
        p = pts.astype(np.float64)
        dd = np.diff(p, axis=0)
        seg = np.sqrt((dd[:, 0] * dd[:, 0] + dd[:, 1] * dd[:, 1]) + dd[:, 2] * dd[:, 2])
        ends = np.cumsum(counts)
        out = np.zeros(len(counts))
        for j in np.nonzero(counts >= 2)[0]:                     # np.cumsum is sequential, unlike np.sum
            out[j] = np.cumsum(seg[ends[j] - counts[j]:ends[j] - 1])[-1]
        return out

    def check_slen(self, src_pts=None):
        if "SLEN" not in self.sections:
            need(self.N == 0 or self.minor < (4 if self.major == 2 else 5), 64, "SLEN missing")
            return None
        sl = self.sec_array("SLEN", "<f4", self.N)
        off = self.sec("SLEN")[0]
        i = np.nonzero(~np.isfinite(sl) | np.signbit(sl))[0]
        need(len(i) == 0, off + 4 * (i[0] if len(i) else 0), "SLEN length not finite or negative")
        # "+0 for a streamline of fewer than two points" (§5.15), whatever the position encoding
        i = np.nonzero((self.counts < 2) & (sl.view(np.uint32) != 0))[0]
        need(len(i) == 0, off + 4 * (i[0] if len(i) else 0), f"streamline {i[0] if len(i) else 0} has fewer "
             "than two points but a length other than +0")
        L = self.lengths(self.points, self.counts)
        if self.pos_enc == 0:
            i = np.nonzero(L.astype(np.float32).view(np.uint32) != sl.view(np.uint32))[0]
            need(len(i) == 0, off + 4 * (i[0] if len(i) else 0),
                 f"streamline {i[0] if len(i) else 0}: SLEN {sl[i[0]] if len(i) else 0!r}, measured "
                 f"{np.float32(L[i[0]]) if len(i) else 0!r}")
            err = 0.0
        else:
            # §5.15: b is the largest per-axis bound of §5.4 among all the file's voxels
            b = self.B.max(initial=0.0)
            tol = 2 * math.sqrt(3) * b * np.maximum(self.counts - 1, 0) + 1e-6 * np.maximum(1, L)
            dev = np.abs(sl.astype(np.float64) - L)
            i = np.nonzero(dev > tol)[0]
            need(len(i) == 0, off + 4 * (i[0] if len(i) else 0), f"streamline {i[0] if len(i) else 0}: SLEN "
                 f"{sl[i[0]] if len(i) else 0} differs from decoded length by more than §5.15's bound")
            err = float((dev / np.where(tol > 0, tol, 1)).max()) if self.N else 0.0
        self.slen = sl
        return err

    def check_all(self):
        """Everything §7 lists for open and verify, in dependency order."""
        self.parse_container()
        self.parse_meta()
        self.parse_dirs()
        self.parse_voxels()
        self.decode_vertices()
        self.walk()
        self.check_orders()
        self.check_vxix()
        if self.order_set == 2:
            self.vdir_recipe = self.check_vdir_recipe()
        slen_err = self.check_slen()
        prov = self.prov = self.check_prov()
        self.check_converted_point_voxels(prov)
        self.check_values()
        ngroups = self.check_groups()
        self.check_gdat(ngroups)
        return slen_err, prov, ngroups

    def check_prov(self):
        if "PROV" not in self.sections:
            return None
        off, size = self.sec("PROV")
        try:
            prov = json.loads(self.data[off:off + size].decode("utf-8"))
        except (UnicodeDecodeError, ValueError) as e:
            fail(off, f"PROV is not valid UTF-8 JSON: {e}")
        need(isinstance(prov, dict), off, "PROV is not a JSON object")
        # §5.8 writer rules (§7 asks only for valid JSON, so differences are notes): the serialisation,
        # and the converter keys against what META says the file has
        if json.dumps(prov, separators=(",", ":"), sort_keys=True, ensure_ascii=False).encode() != \
                self.data[off:off + size]:
            self.notes.append("PROV is not serialised as §5.8 says (no whitespace, keys in byte order)")
        conv = prov.get("converter", {})
        orders = ["axis", "axis+diag", f"random:{self.K}"][self.order_set]
        lv = conv.get("levels")
        want_lc = lv if isinstance(lv, int) and lv >= 2 and self.P > 0 else 0      # §5.1, §10 --levels 1
        got = (conv.get("voxel_size"), conv.get("orders"), conv.get("positions"), want_lc)
        have = (self.s, orders, ["float32", "packed"][self.pos_enc], self.lc)
        if conv.get("name") == "voxlines" and got != have:
            self.notes.append(f"PROV converter (voxel_size, orders, positions, levels→level_count) {got} "
                              f"!= META's {have}")
        return prov

    def check_values(self):
        """§5.11 VVAL / SVAL: layout, names, reserved zeros, min/max."""
        for name, n in (("VVAL", self.V), ("SVAL", self.N)):
            if name not in self.sections:
                continue
            off, size = self.sec(name)
            need(size >= 16, off, f"{name} too small")
            m, res, cnt = struct.unpack_from("<IIQ", self.data, off)
            need(1 <= m <= 64 and res == 0 and cnt == n, off, f"{name}: set_count {m} / value_count {cnt} "
                 f"(expected 1..64 / {n})")
            D, stride = align(16 + 64 * m, 64), align(4 * n, 64)
            need(size == D + m * stride, self.sections[name][2] + 16, f"{name} size {size} != {D + m * stride}")
            need(not self.buf[off + 16 + 64 * m:off + D].any(), off + 16 + 64 * m, f"{name} padding not zero")
            for k in range(m):
                e = off + 16 + 64 * k
                nm = self.data[e:e + 48]
                need(0 in nm, e, f"{name} set {k}: name has no NUL")
                txt, rest = nm.split(b"\0", 1)
                need(not any(rest), e, f"{name} set {k}: name not NUL-padded")
                try:
                    txt.decode("utf-8")
                except UnicodeDecodeError:
                    fail(e, f"{name} set {k}: name not UTF-8")
                lo, hi, r = struct.unpack_from("<ffQ", self.data, e + 48)
                need(r == 0, e + 56, f"{name} set {k}: reserved not zero")
                a = np.frombuffer(self.data, "<f4", n, off + D + k * stride)
                fin = a[np.isfinite(a)]
                want = (fin.min(), fin.max()) if len(fin) else (np.nan, np.nan)
                need(np.array_equal(np.float32([lo, hi]), np.float32(want), equal_nan=True), e + 48,
                     f"{name} set {k}: min/max {lo},{hi} != finite extremes {want}")
                need(not self.buf[off + D + k * stride + 4 * n:off + D + (k + 1) * stride].any(),
                     off + D + k * stride + 4 * n, f"{name} set {k}: padding not zero")
                if name == "VVAL" and self.L:
                    # §5.11: a connecting vertex carries the value of the vertex it copies
                    nl = np.nonzero(~self.last)[0]
                    a = a.view(np.uint32)
                    i = np.nonzero(a[self.start[nl] + self.m[nl]] != a[self.start[nl + 1]])[0]
                    need(len(i) == 0, off + D + k * stride + 4 * int(self.start[nl[i[0]]] + self.m[nl[i[0]]])
                         if len(i) else 0, f"VVAL set {k}: a connecting vertex's value is not the next "
                         "voxline's first value (§5.11)")

    def check_groups(self):
        """§5.9 GRPS walked whole (members in range, strictly increasing)."""
        if "GRPS" not in self.sections:
            return 0
        off, size = self.sec("GRPS")
        end, p = off + size, off + 8
        g, res = struct.unpack_from("<II", self.data, off)
        need(res == 0, off + 4, "GRPS reserved not zero")
        for k in range(g):
            need(p + 4 <= end, p, f"GRPS group {k} runs past the section")
            ln = struct.unpack_from("<I", self.data, p)[0]
            nm = self.data[p + 4:p + 4 + ln]
            need(p + 4 + ln <= end and b"\0" not in nm, p, f"GRPS group {k}: bad name")
            q = off + align(p + 4 + ln - off, 8)
            need(not any(self.data[p + 4 + ln:q]), p + 4 + ln, "GRPS name padding not zero")
            need(q + 8 <= end, q, "GRPS member_count past the section")
            mc = struct.unpack_from("<Q", self.data, q)[0]
            need(mc <= (end - q - 8) // 8, q, "GRPS members past the section")
            mem = np.frombuffer(self.data, "<u8", mc, q + 8)
            need(mc == 0 or (mem[-1] < self.N and (np.diff(mem.astype(np.int64)) > 0).all()), q + 8,
                 f"GRPS group {k}: members out of range or not strictly increasing")
            p = q + 8 + 8 * mc
        need(p == end, p, "GRPS has bytes after its last group")
        return g

    def check_gdat(self, group_count):
        """§5.13 GDAT parsed whole: entries of 8-byte-aligned parts, unique (group, name)."""
        if "GDAT" not in self.sections:
            return 0
        off, size = self.sec("GDAT")
        end = off + size
        need(size >= 8, off, "GDAT shorter than its 8-byte head")
        count, res = struct.unpack_from("<II", self.data, off)
        need(res == 0, off + 4, "GDAT reserved not zero")
        elem = {1: 1, 2: 2, 3: 4, 4: 8, 5: 1, 6: 2, 7: 4, 8: 8, 9: 2, 10: 4, 11: 8}
        seen, p = set(), off + 8
        for k in range(count):
            need(p + 16 <= end, p, f"GDAT entry {k} runs past the section")
            grp, dt, r2, n, ln = struct.unpack_from("<IHHII", self.data, p)
            need(grp < group_count, p, f"GDAT entry {k}: group {grp} ≥ group_count {group_count}")
            need(dt in elem and r2 == 0, p + 4, f"GDAT entry {k}: dtype {dt} / reserved {r2}")
            need(1 <= n <= 2**20 and 1 <= ln <= 4096, p + 8, f"GDAT entry {k}: components/name_length")
            name = self.data[p + 16:p + 16 + ln]
            need(b"\0" not in name and b"/" not in name, p + 16, f"GDAT entry {k}: name has NUL or /")
            need((grp, name) not in seen, p, f"GDAT entry {k}: (group, name) repeated")
            seen.add((grp, name))
            q = off + align(p + 16 + ln - off, 8)          # padding counted from the payload's start
            r = off + align(q + n * elem[dt] - off, 8)
            need(r <= end, q, f"GDAT entry {k}: values run past the section")
            need(not any(self.data[p + 16 + ln:q]) and not any(self.data[q + n * elem[dt]:r]), p,
                 f"GDAT entry {k}: padding not zero")
            p = r
        need(p == end, p, "GDAT: bytes after the last entry")
        return count


def read_tck_float64(path):
    """Fallback for what nibabel refuses (Float64 TCK): header up to END, data at 'file: . OFFSET',
    triplets, a NaN triplet ends a streamline, an Inf triplet ends the file."""
    raw = open(path, "rb").read()
    head = raw[:raw.index(b"\nEND\n")].decode("latin-1").splitlines()
    kv = {l.split(":", 1)[0].strip(): l.split(":", 1)[1].strip() for l in head[1:] if ":" in l}
    dt = {"Float32LE": "<f4", "Float32BE": ">f4", "Float64LE": "<f8", "Float64BE": ">f8"}[kv["datatype"]]
    pts = np.frombuffer(raw, dt, offset=int(kv["file"].split()[1]))
    pts = pts[:len(pts) // 3 * 3].reshape(-1, 3)
    inf = np.nonzero(np.isinf(pts).any(1))[0]
    pts = pts[:inf[0] if len(inf) else len(pts)]
    nan = np.nonzero(np.isnan(pts).any(1))[0]
    lens = np.diff(np.r_[-1, nan]) - 1
    return lens, pts[~np.isnan(pts).any(1)].astype(np.float64)


def face_points(pts, counts, o, s):
    """§6.3: the points the converter inserts at voxel faces, for f32 source points `pts` (streamlines of
    `counts` points), in file order. Returns (points f32[n,3], voxel entered i64[n,3], index of the step's
    first point)."""
    p = pts.astype(np.float64)
    v = np.floor((p - o) / s).astype(np.int64)                 # §6.1
    last = np.cumsum(counts)[counts > 0] - 1                   # a streamline's last point starts no step
    step = np.ones(len(p), bool)
    step[last] = False
    step[-1:] = False
    i_long = np.nonzero(step[:-1] & (np.abs(v[1:] - v[:-1]).max(1, initial=0) > 1))[0] if len(p) > 1 else []
    out_p, out_v, out_i = [], [], []
    for i in i_long:
        a, b, u, w = p[i], p[i + 1], v[i], v[i + 1]
        faces = []                                             # (t, axis, direction)
        for c in range(3):
            d = 1 if w[c] > u[c] else -1
            for k in range(u[c], w[c], d):                     # k from u_c towards w_c, not reaching it
                plane = o[c] + s * (k + 1) if d > 0 else o[c] + s * k
                t = (plane - a[c]) / (b[c] - a[c])
                faces.append((min(1.0, max(0.0, t)), c, d))    # clamped to [0, 1]
        cur = u.copy()
        # ascending t (x before y before z at equal t); faces at the same t are crossed at once
        for t, same in itertools.groupby(sorted(faces), key=lambda f: f[0]):
            for _, c, d in same:
                cur[c] += d
            out_p.append(np.float32(a + t * (b - a)))          # binary64, each operation rounded, to f32
            out_v.append(cur.copy())
            out_i.append(i)
    return (np.array(out_p, np.float32).reshape(-1, 3), np.array(out_v, np.int64).reshape(-1, 3),
            np.array(out_i, np.int64))


def tck_header(path):
    """§5.8: the lines between `mrtrix tracks` and `END`, `file` included, each split at its first `:`,
    both sides trimmed, as an object of arrays (a repeated key's values in file order, a line without `:`
    continuing the previous value), bad UTF-8 → U+FFFD."""
    raw = open(path, "rb").read(1 << 20)
    end = raw.find(b"\nEND\n")
    if end < 0:
        raise Usage(f"{path}: no TCK header END")
    kv, last = {}, None
    for line in raw[:end].decode("utf-8", errors="replace").split("\n")[1:]:
        if ":" in line:
            k, v = line.split(":", 1)
            last = kv.setdefault(k.strip(), [])
            last.append(v.strip())
        elif last is not None and line.strip():
            last[-1] += "\n" + line.strip()       # §5.8: a line without ":" continues the previous value
    return kv


def check_prov_source(f, prov, src, report):
    """§5.8: PROV names the source by name, format, size, XXH3_128 (32 lowercase hex digits, high 64
    bits first: xxhash's hexdigest), coordinate type in the format's words, and vox_to_ras (null for TCK)."""
    if prov is None:                                # PROV is optional (§4): nothing to check
        f.notes.append("no PROV: the source record was not checked")
        return
    info, off = prov.get("source"), f.sec("PROV")[0]
    need(isinstance(info, dict), off, "PROV has no source object (§5.8)")
    raw = open(src, "rb").read()
    want = {"name": os.path.basename(src), "format": "tck", "bytes": len(raw),
            "xxh3_128": xxhash.xxh3_128(raw).hexdigest(), "vox_to_ras": None,
            "dtype": tck_header(src).get("datatype", [None])[0]}
    want["header"] = tck_header(src)
    for k, v in want.items():
        need(info.get(k, "(missing)") == v, off, f"PROV source.{k} is {info.get(k, '(missing)')!r}, "
             f"{src} gives {v!r} (§5.8)")
    report(f"  PROV source matches {src} (name, format, bytes, xxh3_128, dtype, vox_to_ras null, header)")


def compare(f, src, report):
    """The file against its source: points (§8), and for a TCK every vertex the converter must have made
    from it (§6.1 voxels, §6.3 face points, connecting copies, §5.4 packing, §5.3 tight bounds)."""
    import nibabel as nib
    exact = src.lower().endswith(".tck")
    try:
        sl = nib.streamlines.load(src).streamlines
        lens = np.asarray(sl._lengths, np.int64)
        data = np.asarray(sl.get_data()).reshape(-1, 3)
    except Exception as e:          # nibabel reads only float32 TCK
        if not exact:
            raise Usage(f"nibabel cannot read {src}: {str(e)[:80]}")
        report(f"  compare: nibabel cannot read {src} ({str(e)[:60]}...); using the built-in TCK reader")
        try:
            lens, data = read_tck_float64(src)
        except Exception as e2:
            raise Usage(f"cannot read the source {src}: {type(e2).__name__}: {str(e2)[:80]}")
    counts = f.counts
    if len(lens) < f.N and len(lens) == int((f.counts > 0).sum()):
        # nibabel drops empty streamlines (a NaN triplet right after another); the file keeps them (§5.7)
        report(f"  compare: the source reader dropped {f.N - len(lens)} empty streamline(s); comparing the rest")
        counts = f.counts[f.counts > 0]
    need(len(lens) == len(counts), 0, f"source has {len(lens)} streamlines, the file {f.N}")
    need(np.array_equal(lens, counts), 0, "per-streamline point counts differ from the source")
    # §8: a float32 source is stored bit-exactly; a float64 one rounded to nearest f32
    ref = data.astype(np.float32)
    if exact:
        check_prov_source(f, f.prov, src, report)
        f.check_point_voxels(ref)                                   # §6.1 from the exact source points
        # §6.3: the face points, where they are in the walk and the voxels they start
        fp, fv, fi = face_points(ref, f.counts, f.origin, f.s)
        js = np.nonzero(f.syn)[0]
        need(len(fp) == len(js), f.sec("META")[0] + 40, f"§6.3 inserts {len(fp)} face points, the file has {len(js)}")
        before = (np.cumsum(f.own) - f.own)[js]                      # own points before each synthetic voxline
        e = np.nonzero((before != fi + 1) | (f.vt["coord"][f.voxel[js]] != fv).any(1))[0]
        need(len(e) == 0, f.sec("VXLN")[0] + 8 * int(js[e[0]] if len(e) else 0),
             f"face point {e[0] if len(e) else 0}: not where §6.3 puts it (step or voxel entered)")
        # every vertex as §6.2/§6.3 make it: own points, face points, connecting copies of the next first
        ex = np.empty((f.V, 3), np.float32)
        ex[f.pidx] = ref
        ex[f.start[js]] = fp
        nl = np.nonzero(~f.last)[0]
        ex[f.start[nl] + f.m[nl]] = ex[f.start[nl + 1]]
        at = lambda i: f.sec("VERT")[0] + (12 if f.pos_enc == 0 else 4) * int(i)
        if f.pos_enc == 0:
            i = np.nonzero((ex.view(np.uint32) != f.pos.view(np.uint32)).any(1))[0]
            need(len(i) == 0, at(i[0] if len(i) else 0), f"vertex {i[0] if len(i) else 0}: "
                 f"{f.pos[i[0]] if len(i) else 0}, §6.2/§6.3 from the source give {ex[i[0]] if len(i) else 0}")
        else:
            lo, hi = f.vt["tmin"], f.vt["tmax"]
            xlo = np.full((f.nvox, 3), np.inf, np.float32)
            xhi = np.full((f.nvox, 3), -np.inf, np.float32)
            np.minimum.at(xlo, f.vox_of, ex)
            np.maximum.at(xhi, f.vox_of, ex)
            i = np.nonzero((xlo != lo).any(1) | (xhi != hi).any(1))[0]         # §5.4 "tight bounds stay
            need(len(i) == 0, f.sec("VOXT")[0] + 64 * int(i[0] if len(i) else 0) + 16,  # those of the exact"
                 f"voxel {i[0] if len(i) else 0}: tight bounds are not its exact vertices' extremes (§5.4)")
            q = pack_q(ex, lo[f.vox_of], hi[f.vox_of])
            i = np.nonzero((q != f.q).any(1))[0]
            need(len(i) == 0, at(i[0] if len(i) else 0), f"vertex {i[0] if len(i) else 0}: quanta "
                 f"{f.q[i[0]] if len(i) else 0}, §5.4 packs {ex[i[0]] if len(i) else 0} to {q[i[0]] if len(i) else 0}")
    # the error against the source, and for non-TCK sources the §8 tolerance of the old check
    # (nibabel maps TRK voxmm to RAS itself, in float32, where §8 maps in binary64 and rounds once)
    slack = 0.0 if exact else np.spacing(np.abs(ref)).astype(np.float64)
    e = np.abs(f.points.astype(np.float64) - ref.astype(np.float64))
    B = np.broadcast_to((f.B[f.point_vox] if f.pos_enc else 0) + slack, e.shape)
    i = np.nonzero((e > B).any(1))[0]
    need(len(i) == 0, 0, f"point {i[0] if len(i) else 0}: error {e[i[0]] if len(i) else 0} > {B[i[0]] if len(i) else 0} (§5.4, §8)")
    err = float(e.max()) if len(e) else 0.0
    ratio = float((e / np.where(B > 0, B, 1)).max()) if len(e) else 0.0
    # §5.15: SLEN is measured from the source points, so it must match them to the bit
    if "SLEN" in f.sections and exact:
        L = f.lengths(ref, counts).astype(np.float32)
        i = np.nonzero(L.view(np.uint32) != f.slen[f.counts > 0 if len(counts) < f.N else slice(None)]
                       .view(np.uint32))[0]
        need(len(i) == 0, f.sec("SLEN")[0] + 4 * (i[0] if len(i) else 0),
             f"streamline {i[0] if len(i) else 0}: SLEN != §5.15 length of the source points")
    what = ("every vertex bit-exact (§8, §6.3)" if f.pos_enc == 0 else
            "every packed word as §5.4 packs the exact vertices") if exact else "within one float32 spacing"
    report(f"  compare: {len(data)} source points, {f.synth} face points; {what}; max |error| {err:.3g} mm"
           f"{f', largest error/B {ratio:.3f}' if f.pos_enc else ''}"
           f"{'; SLEN bit-exact to the source' if 'SLEN' in f.sections and exact else ''}")
    return err


def parse_command_line(description, usage, add_arguments):
    """A spec reader's command line: a file, --compare FILE, -q, and what `add_arguments` adds. Returns the
    arguments and the function that prints progress (nothing with -q), or None when a file named is not readable;
    a malformed command line prints `usage` and exits 2."""
    ap = argparse.ArgumentParser(description=description)
    ap.error = lambda msg: (print(f"usage error: {msg} (usage: {usage})", file=sys.stderr), sys.exit(2))
    add_arguments(ap)
    ap.add_argument("-q", "--quiet", action="store_true", help="print only the one-line verdict")
    a = ap.parse_args()
    for p in [a.file] + ([a.compare] if a.compare else []):
        if not os.path.isfile(p) or not os.access(p, os.R_OK):
            print(f"usage error: {p}: not a readable file", file=sys.stderr)
            return None
    return a, ((lambda s: None) if a.quiet else print)


def main():
    def add_arguments(ap):
        ap.add_argument("file")
        ap.add_argument("--compare", metavar="SOURCE", help="the source tractogram (TCK for the exact checks)")
    parsed = parse_command_line(__doc__.split("\n")[0], "vxl_spec_reader.py FILE.vxl [--compare SOURCE.tck] [-q]",
                                add_arguments)
    if parsed is None:
        return 2
    a, say = parsed
    self_test_depths()
    f = VxlFile(a.file, say)
    try:
        slen_err, prov, ngroups = f.check_all()
        say(f"{a.file}: vxl {f.major}.{f.minor}, sections " +
            " ".join(f"{k}:{v[1]}" for k, v in f.sections.items()))
        say(f"  N={f.N} P={f.P} V={f.V} S={f.S} L={f.L} synthetic={f.synth} voxels={f.nvox} "
            f"grid={f.dims.tolist()} s={f.s} K={f.K} order_set={f.order_set} "
            f"positions={'packed' if f.pos_enc else 'float32'} levels={f.lc} groups={ngroups}")
        if f.pos_enc and slen_err is not None:
            say(f"  largest §5.4 bound B {f.B.max(initial=0) * 1000:.3f} um; SLEN/decoded deviation up to "
                f"{slen_err:.3f} of §5.15's bound")
        say(f"  orders: {f.nvox} voxels × {f.levels} level(s) × K={f.K} checked "
            f"(permutation, §6.4 key order, {f.ties} equal-key neighbours ordered by index)")
        if f.order_set == 2:
            say(f"  VDIR {'is' if f.vdir_recipe else 'is NOT'} what §5.10's recipe gives")
        if a.compare:
            compare(f, a.compare, say)
        for n in f.notes:
            say(f"  note: {n}")
    except Invalid as e:
        print(f"{a.file}: INVALID: {e}", file=sys.stderr)
        return 1
    except Usage as e:
        print(f"usage error: {e}", file=sys.stderr)
        return 2
    except (ValueError, IndexError, OverflowError, MemoryError, KeyError) as e:
        # a damaged table can still send a lookup out of range before a rule names it
        print(f"{a.file}: INVALID (not readable as the spec describes: {type(e).__name__}: {e})",
              file=sys.stderr)
        return 1
    print(f"{a.file}: OK ({f.nvox} voxels, {f.P} points{', matches ' + a.compare if a.compare else ''}"
          f"{f', {len(f.notes)} note(s)' if f.notes else ''})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
