#!/usr/bin/python3
"""A second, independent reader of the .vxlz package format, written from spec/vxlz-package-v2.md and
spec/vxl-format.md alone (no code of the C++ implementation).

    /usr/bin/python3 scripts/vxlz_spec_reader.py PACKAGE.vxlz [--compare UNPACKED.vxl] [--draco-dump PATH] [-q]

It validates the package in the order of spec §8 (steps 1–7), decodes every section (§3–§6: varints, zigzag,
zlib sections, VOXC/STRL/VXLV/VXLC, GRPS, PVAL/SVAL codings, GDAT, the position chunks with joint symbols and
escapes, both predictors, level order with depth(j) of .vxl §6.5, dequantisation of §6) and rebuilds the
.vxl content of §7 (META with recomputed bounds, STRM, VXLN, VOXT, LODS, VERT with connecting vertices, SLEN,
PROV with the "vxlz" key, GRPS, GDAT, VVAL/SVAL). With --compare UNPACKED.vxl (made by `voxlines unpack`) it
checks that file with scripts/vxl_spec_reader.py (spec .vxl §7: open and verify, so its orders are sorted by
.vxl §6.4 from its own vertices) and requires every part the package determines to equal the rebuild: float32
vertices bit for bit, packed words as .vxl §5.4 packs the decoded vertices, counts, tables, value bits,
groups, PROV. Since .vxl §6.4's order is unique (ties broken by index), "sorted by §6.4 from vertices equal to
ours" means "equal to the orders we would compute".

Draco buffers are decoded by tests/spec/draco_cloud_dump.cpp (libdraco's public API): --draco-dump PATH names
the built program; without it, $VXLZ_DRACO_DUMP, else it is compiled once into /tmp with g++ -ldraco.

Exit status: 0 valid (and equal), 1 invalid (or different), 2 usage error. The last line is one line:
"FILE: OK ..." or "FILE: INVALID: byte N: what was expected" (or "UNSUPPORTED: ..."); -q prints only that.
Rules the spec states for writers but §8 does not ask a reader to enforce are reported as notes.
"""
import argparse
import hashlib
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
import zlib

import numpy as np
import xxhash

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import vxl_spec_reader as vr  # noqa: E402  (the .vxl reader written from spec/vxl-format.md alone)

MAGIC = b"\x89VXZ\r\n\x1a\n"
# §2.2: id -> (required, encoding)
KNOWN = {b"PACK": 1, b"META": 1, b"DIRS": 1, b"VOXC": 1, b"STRL": 1, b"VXLV": 1, b"VXLC": 1, b"PROV": 0,
         b"GRPS": 0, b"PVAL": 0, b"SVAL": 0, b"GDAT": 0, b"CHNK": 1, b"CHKS": 0, b"POSD": 1}
WRITER_ORDER = [k.decode() for k in KNOWN]
F32_MAX = float(np.finfo(np.float32).max)
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


class Invalid(Exception):
    def __init__(self, msg, kind="input"):
        super().__init__(msg)
        self.kind = kind


class Different(Exception):
    """The unpacked .vxl differs from what the package determines."""


def fail(off, msg, kind="input"):
    raise Invalid(f"byte {off}: {msg}", kind)


def need(cond, off, msg, kind="input"):
    if not cond:
        fail(off, msg, kind)


def first(mask):
    idx = np.nonzero(mask)[0]
    return int(idx[0]) if len(idx) else None


def varints(raw, where, base):
    """All unsigned LEB128 varints of `raw` (§1), vectorised. Returns (values u64, start of each). Refuses a
    varint cut off at the end, longer than 10 bytes, or not fitting 64 bits. `where` names the stream,
    `base` is the section payload's offset (messages name the inflated byte inside it)."""
    b = np.frombuffer(raw, np.uint8)
    if len(b) == 0:
        return np.zeros(0, np.uint64), np.zeros(0, np.int64), 0
    need(b[-1] < 0x80, base, f"{where}: inflated byte {len(b) - 1}: a varint runs past the end of the stream")
    ends = np.nonzero(b < 0x80)[0]
    starts = np.r_[0, ends[:-1] + 1]
    lens = ends - starts + 1
    i = first(lens > 10)
    need(i is None, base, f"{where}: inflated byte {starts[i] if i is not None else 0}: varint of more than 10 bytes")
    i = first((lens == 10) & (b[ends] > 1))
    need(i is None, base, f"{where}: inflated byte {starts[i] if i is not None else 0}: varint does not fit 64 bits")
    # §1: writers write the shortest form, readers accept a longer one: a note
    overlong = int(((lens > 1) & (b[ends] == 0)).sum())
    idx = np.arange(len(b)) - np.repeat(starts, lens)
    v = (b & 0x7F).astype(np.uint64) << (7 * idx).astype(np.uint64)
    return np.bitwise_or.reduceat(v, starts), starts, overlong


def unzigzag(u):
    u = u.astype(np.uint64)
    return (u >> np.uint64(1)).astype(np.int64) ^ -(u & np.uint64(1)).astype(np.int64)


def zigzag_py(n):
    return (n << 1) ^ (n >> 63)


class Package:
    def __init__(self, path, say, dump):
        self.path, self.say, self.dump = path, say, dump
        with open(path, "rb") as f:
            self.data = f.read()
        self.notes = []

    # ---------------- §8 step 1: header ----------------
    def step1(self):
        d = self.data
        need(len(d) >= 64, 0, f"file of {len(d)} bytes is shorter than the 64-byte header")
        need(d[:8] == MAGIC, 0, f"magic {d[:8].hex()}, expected {MAGIC.hex()}")
        (self.major, self.minor, hsize, fsize, tab, cnt, flags, hsum) = struct.unpack_from("<HHIQQIIQ", d, 8)
        need(self.major == 2, 8, f"version_major {self.major}, this reader knows 2"
             + (" (a 1.0 package: pack the .vxl again)" if self.major == 1 else ""), "unsupported")
        need(hsize == 64, 12, f"header_size {hsize}, expected 64")
        need(fsize == len(d), 16, f"file_size {fsize}, the file has {len(d)} bytes")
        need(tab == 64, 24, f"section_table_offset {tab}, expected 64")
        need(1 <= cnt <= 32, 32, f"section_count {cnt}, expected 1 … 32")
        need(flags == 0, 36, f"flags {flags:#x}, expected 0")
        need(d[48:64] == bytes(16), 48, "reserved header bytes not zero")
        self.tab_end = 64 + 32 * cnt
        need(self.tab_end <= fsize, 32, f"section table ({cnt} entries) ends at {self.tab_end}, past the file")
        h = xxhash.xxh3_64(d[:40] + bytes(8) + d[48:self.tab_end]).intdigest()
        need(h == hsum, 40, f"header_checksum {hsum:#018x}, computed {h:#018x}")
        self.count = cnt

    # ---------------- step 2: table ----------------
    def step2(self):
        d, p = self.data, self.tab_end
        self.sec, self.entry = {}, {}
        for i in range(self.count):
            e = 64 + 32 * i
            sid, fl, off, size, csum = struct.unpack_from("<4sIQQQ", d, e)
            name = sid.decode("latin-1")
            need(fl & ~1 == 0, e + 4, f"{name!r}: flags {fl:#x}, only bit 0 (required) allowed")
            need(name not in self.sec, e, f"section id {name!r} appears twice")
            need(off == p, e + 8, f"{name!r}: offset {off}, expected {p} (payloads back to back from the table)")
            need(size <= len(d) - off, e + 16, f"{name!r}: size {size} runs past the end of the file")
            if sid in KNOWN:
                if bool(fl & 1) != bool(KNOWN[sid]):   # §2.2: readers do not check it; a note
                    self.notes.append(f"{name}: required flag {fl & 1}, §2.2's table says {KNOWN[sid]}")
            else:
                need(not fl & 1, e, f"unknown required section {name!r}", "unsupported")
                self.notes.append(f"unknown optional section {name!r} skipped")
            if not all(0x20 <= c <= 0x7E for c in sid):
                self.notes.append(f"section id {sid!r} is not printable ASCII (the .vxl's rule; §2.2: not checked)")
            self.sec[name], self.entry[name] = (off, size, csum), e
            p = off + size
        need(p == len(d), 16, f"the last payload ends at {p}, the file at {len(d)}")
        for s in ("PACK", "META", "DIRS", "VOXC", "STRL", "VXLV", "VXLC", "CHNK", "POSD"):
            need(s in self.sec, 64, f"required section {s} missing")
        ids = [k for k in self.sec if k in WRITER_ORDER]
        if ids != sorted(ids, key=WRITER_ORDER.index):
            self.notes.append(f"sections {' '.join(self.sec)} not in §2.2's writer order")

    # ---------------- step 3: checksums ----------------
    def step3(self):
        for name, (off, size, csum) in self.sec.items():
            h = xxhash.xxh3_64(self.data[off:off + size]).intdigest()
            need(h == csum, self.entry[name] + 24, f"{name}: checksum {csum:#018x}, computed {h:#018x} over "
                 f"bytes {off} … {off + size}")

    def payload(self, name):
        off, size, _ = self.sec[name]
        return off, self.data[off:off + size]

    # ---------------- step 4: PACK, META, DIRS, CHNK, CHKS ----------------
    def step4(self):
        off, p = self.payload("PACK")
        need(len(p) == 128, self.entry["PACK"] + 16, f"PACK size {len(p)}, expected 128")
        (b, pred, o0, o1, o2, q, R, n, C, nch, eb, maxe, rmse, t, lc) = struct.unpack_from("<II3dddQQQdddII", p)
        self.b, self.pred, self.o, self.q, self.R, self.n = b, pred, np.array([o0, o1, o2]), q, R, n
        self.C, self.nch, self.eb, self.maxe, self.rmse, self.t, self.plc = C, nch, eb, maxe, rmse, t, lc
        need(11 <= b <= 16, off, f"quantization_bits {b}, expected 11 … 16")
        need(pred in (1, 2), off + 4, f"predictor {pred}, this reader knows 1 and 2", "unsupported")
        need(lc == 0 if pred == 1 else 2 <= lc <= 8, off + 100,
             f"level_count {lc}, expected {'0 with predictor 1' if pred == 1 else '2 … 8 with predictor 2'}")
        need(all(math.isfinite(x) for x in self.o), off + 8, f"quant_origin {self.o} not finite")
        need(math.isfinite(q) and q > 0, off + 32, f"quantum {q}, expected finite and > 0")
        top = self.o + (2**b - 1) * q
        need((np.abs(self.o) <= F32_MAX).all() and (np.abs(top) <= F32_MAX).all(), off + 8,
             "the quantisation cube leaves the float32 range")
        need(1 <= C < 2**31, off + 56, f"chunk_points {C}, expected 1 ≤ C < 2^31")
        need(nch == -(-n // C), off + 64, f"chunk_count {nch}, ⌈n / C⌉ = {-(-n // C)}")
        need(1 <= t <= 5, off + 96, f"joint_bits {t}, expected 1 … 5")
        need(p[104:128] == bytes(24), off + 104, "PACK reserved bytes not zero")
        # writer-side relations §3/§6 states but §8 does not check: notes only
        if not (math.isfinite(R) and R >= 0):
            self.notes.append(f"PACK.range {R} not finite ≥ 0")
        elif (R / (2**b - 1) if R > 0 else 1.0) != q:
            self.notes.append(f"PACK.quantum {q!r} != R/(2^b−1) = {R / (2**b - 1)!r} (§3)")
        if math.isfinite(R):
            M = max(max(abs(x), abs(x + R)) for x in self.o)
            want = (q / 2 if R > 0 else 0) + 2.0**-23 * M
            if want != eb:
                self.notes.append(f"PACK.error_bound {eb!r} != q/2 + 2^−23·M = {want!r} (§3, §6)")
        # META
        moff, m = self.payload("META")
        need(len(m) == 256, self.entry["META"] + 16, f"META size {len(m)}, expected 256")
        self.meta_raw = m
        f = struct.unpack_from("<6QIId3d3iI3d3dII", m)
        (self.N, self.P, self.V, self.S, self.L, self.synth, self.nvox, self.K, self.s) = f[:9]
        self.gorigin, self.dims = np.array(f[9:12]), np.array(f[12:15], np.int64)
        self.order_set, self.mbmin, self.mbmax = f[15], np.array(f[16:19]), np.array(f[19:22])
        pe, self.mlc = f[22], f[23]
        need(pe == 0, moff + 152, f"META position_encoding {pe}, a package's is 0 (§4.1)")
        need(m[160:256] == bytes(96), moff + 160, "META reserved bytes not zero")
        need(math.isfinite(self.s) and self.s > 0, moff + 56, f"voxel_size {self.s}, expected finite and > 0")
        need(1 <= self.K <= 64, moff + 52, f"stored_order_count {self.K}, expected 1 … 64")
        need(self.order_set in (0, 1, 2), moff + 100, f"order_set {self.order_set}, expected 0, 1 or 2")
        need(self.order_set != 0 or self.K == 3, moff + 52, "order_set 0 (axis) needs K = 3")
        need(self.order_set != 1 or self.K == 7, moff + 52, "order_set 1 (axis+diag) needs K = 7")
        need(self.nvox < 2**31, moff + 48, f"voxel_count {self.nvox} ≥ 2^31")
        need((self.dims >= 0).all(), moff + 88, f"grid_dims {self.dims} negative")
        need(all(math.isfinite(x) for x in self.gorigin), moff + 64, "grid_origin not finite")
        # the grid rule of .vxl §7 step 5 on the shipped bounds
        need((self.mbmin <= self.mbmax).all(), moff + 104, f"bounds_min {self.mbmin} > bounds_max {self.mbmax}")
        need((np.abs(self.gorigin - self.mbmin) <= self.s).all(), moff + 64, "|grid_origin − bounds_min| > s")
        g = np.floor((self.mbmax - self.mbmin) / self.s) + 1
        need((np.abs(self.dims - g) <= 1).all(), moff + 88, f"grid_dims {self.dims} not within 1 of {g}")
        need(self.P + self.synth == n, moff + 8, f"point_count {self.P} + synthetic {self.synth} != PACK n = {n}")
        # §4.1, §8 step 4: the package's META has level_count 0 (PACK.level_count carries Λ)
        need(self.mlc == 0, moff + 156, f"META.level_count {self.mlc}, expected 0 in a package (§4.1)")
        if not (self.o == self.gorigin).all() and n:
            self.notes.append(f"quant_origin {self.o} != grid_origin {self.gorigin} (§6 says they are equal)")
        # §4.1, §8 step 4: package 2.x holds one direction set; a package that says order_set 2 opens, and the
        # unpacker refuses it before decoding anything: this reader, which decodes, refuses it here
        need(self.order_set != 2, moff + 100, "order_set 2 (per-voxel directions): not in a 2.x package (§4.1)",
             "unsupported")
        # DIRS
        doff, dr = self.payload("DIRS")
        need(len(dr) == 16 * self.K, self.entry["DIRS"] + 16, f"DIRS size {len(dr)}, expected K × 16 = {16 * self.K}")
        dirs = np.frombuffer(dr, np.dtype([("v", "<f4", 3), ("r", "<u4")]))
        i = first(dirs["r"] != 0)
        need(i is None, doff + 16 * (i or 0) + 12, f"DIRS entry {i}: reserved not zero")
        ln = np.sqrt((dirs["v"].astype(np.float64) ** 2).sum(1))
        i = first(np.abs(ln - 1) > 1e-5)          # §8 step 4: unit vectors within 10^−5
        need(i is None, doff + 16 * (i or 0), f"DIRS entry {i}: not a unit vector (length {ln[i or 0] if len(ln) else 0})")
        self.dirs_raw = dr
        # CHNK / CHKS
        coff, ch = self.payload("CHNK")
        need(len(ch) == 16 * nch, self.entry["CHNK"] + 16, f"CHNK size {len(ch)}, expected chunk_count × 16 = {16 * nch}")
        self.chnk = np.frombuffer(ch, "<u8").reshape(-1, 2).astype(object)   # exact sums, no u64 wrap
        posd_off, posd_size, _ = self.sec["POSD"]
        tot = sum(int(x) for x in self.chnk.ravel())
        need(tot == posd_size, coff, f"CHNK sizes sum to {tot}, POSD holds {posd_size} bytes")
        self.chunk_at = posd_off + np.r_[0, np.cumsum(np.array([int(a) + int(b) for a, b in self.chnk], dtype=np.int64))]
        if "CHKS" in self.sec:
            koff, ks = self.payload("CHKS")
            need(len(ks) == 8 * nch, self.entry["CHKS"] + 16, f"CHKS size {len(ks)}, expected chunk_count × 8 = {8 * nch}")
            sums = np.frombuffer(ks, "<u8")
            for c in range(nch):
                h = xxhash.xxh3_64(self.data[self.chunk_at[c]:self.chunk_at[c + 1]]).intdigest()
                need(h == int(sums[c]), koff + 8 * c, f"CHKS: chunk {c}'s XXH3_64 is {h:#018x}, entry {int(sums[c]):#018x}")
            if pred != 2:
                self.notes.append("CHKS with predictor 1 (§5.3: writers write it exactly with predictor 2)")
        elif pred == 2:
            self.notes.append("level order without CHKS (a 2.3 writer's package)")
        # version_minor (§2.1): informative for readers, a note
        has = self.sec.__contains__
        want = (4 if has("CHKS") else 3) if pred == 2 else 2 if has("GDAT") else 1 if (has("PVAL") or has("SVAL")) else 0
        if self.minor != want:
            self.notes.append(f"version 2.{self.minor}, §2.1 gives 2.{want} for these sections")

    # ---------------- step 5: zlib sections and varint streams ----------------
    def inflate(self, name, off, payload, where=None):
        where = where or name
        need(len(payload) >= 8, off, f"{where}: zlib section of {len(payload)} bytes, shorter than its u64 raw_size")
        raw_size = struct.unpack_from("<Q", payload)[0]
        need(raw_size <= 1100 * (len(payload) - 8) + 64, off,
             f"{where}: raw_size {raw_size} > 1100 × {len(payload) - 8} + 64 (§1)")
        z = zlib.decompressobj()
        try:
            raw = z.decompress(payload[8:], raw_size + 1)
        except zlib.error as e:
            fail(off + 8, f"{where}: not a zlib stream ({e})")
        need(len(raw) == raw_size and not z.unconsumed_tail, off, f"{where}: inflates past raw_size {raw_size}")
        need(z.eof, off + 8, f"{where}: zlib stream incomplete (inflated {len(raw)} of {raw_size} bytes)")
        need(not z.unused_data, off + len(payload) - len(z.unused_data),
             f"{where}: {len(z.unused_data)} bytes after the end of the zlib stream")
        return raw

    def step5(self):
        self.raw = {}
        for name in ("VOXC", "STRL", "VXLV", "VXLC", "PROV", "GRPS", "GDAT"):
            if name in self.sec:
                off, p = self.payload(name)
                self.raw[name] = self.inflate(name, off, p)
        self.overlong = 0

        def ints(name, count):
            off = self.sec[name][0]
            v, st, ol = varints(self.raw[name], name, off)
            self.overlong += ol
            need(len(v) == count, off, f"{name}: {len(v)} varints, expected exactly {count}")
            return v
        self.voxc = unzigzag(ints("VOXC", 3 * self.nvox)).reshape(-1, 3)
        self.strl = ints("STRL", self.N).astype(np.int64) if self.N < 2**62 else None
        self.vxlc = ints("VXLC", self.L)
        off = self.sec["VXLV"][0]
        self.vxlv, self.vxlv_st, ol = varints(self.raw["VXLV"], "VXLV", off)
        self.overlong += ol
        # VXLV: L codes, each followed by one more varint when 0 (§4.4); consumed exactly
        codes, L = self.vxlv, self.L
        cl = codes.tolist()
        pos, kinds = 0, []
        for _ in range(L):
            need(pos < len(cl), off, f"VXLV: the stream ends after {len(kinds)} of {L} voxlines")
            if cl[pos] == 0:
                need(pos + 1 < len(cl), off, f"VXLV: inflated byte {len(self.raw['VXLV'])}: code 0 without its difference")
                kinds.append((0, cl[pos + 1], pos))
                pos += 2
            else:
                kinds.append((1, cl[pos], pos))
                pos += 1
        need(pos == len(cl), off, f"VXLV: {len(cl) - pos} varints after the {L} voxlines")
        self.vxlv_items = kinds
        if "GRPS" in self.raw:
            self.groups = self.parse_grps()
        if self.overlong:
            self.notes.append(f"{self.overlong} varint(s) not in the shortest form (§1: writers write the shortest)")

    def parse_grps(self):
        raw, off = self.raw["GRPS"], self.sec["GRPS"][0]
        pos = 0

        def vint():
            nonlocal pos
            v, shift = 0, 0
            for k in range(10):
                need(pos < len(raw), off, f"GRPS: inflated byte {pos}: a varint runs past the end")
                c = raw[pos]
                pos += 1
                need(k < 9 or c <= 1, off, f"GRPS: inflated byte {pos - 1}: varint does not fit 64 bits")
                v |= (c & 0x7F) << shift
                shift += 7
                if c < 0x80:
                    return v
            fail(off, f"GRPS: inflated byte {pos}: varint of more than 10 bytes")
        gc = vint()
        need(gc <= len(raw), off, f"GRPS: group_count {gc} larger than the stream")
        groups = []
        for g in range(gc):
            at = pos
            nl = vint()
            need(nl <= len(raw) - pos, off, f"GRPS: inflated byte {at}: group {g}'s name runs past the stream")
            name = raw[pos:pos + nl]
            pos += nl
            mc = vint()
            need(mc <= len(raw) - pos, off, f"GRPS: inflated byte {at}: group {g}: {mc} members cannot fit")
            mem, acc = [], -1
            for k in range(mc):          # the first member, then member_i − member_{i−1} − 1 (§4.6)
                x = vint()
                acc = x if k == 0 else acc + x + 1
                mem.append(acc)
            groups.append((name, mem, at))
        need(pos == len(raw), off, f"GRPS: inflated byte {pos}: {len(raw) - pos} bytes after the last group")
        return groups

    # ---------------- step 6: structure ----------------
    def step6(self):
        vo = self.sec["VOXC"][0]
        c = np.cumsum(self.voxc, 0) if self.nvox else np.zeros((0, 3), np.int64)
        self.coord = c
        i = first(((c < 0) | (c >= self.dims)).any(1))
        need(i is None, vo, f"VOXC: voxel {i} at {c[i] if i is not None else 0}, outside grid_dims {self.dims}")
        key = (c[:, 2] * (int(self.dims[1]) + 1) + c[:, 1]) * (int(self.dims[0]) + 1) + c[:, 0]
        i = first(np.diff(key) <= 0)
        need(i is None, vo, f"VOXC: voxel {(i or 0) + 1} not after voxel {i} in (z, y, x) order")
        if self.nvox:
            need((c.min(0) == 0).all() and (c.max(0) == self.dims - 1).all(), vo,
                 f"VOXC: coordinates run from {c.min(0)} to {c.max(0)}, expected 0 … grid_dims − 1 = {self.dims - 1}")
        so = self.sec["STRL"][0]
        need(int(self.strl.astype(object).sum()) == self.L, so, f"STRL sums to {self.strl.sum()}, voxline_count is {self.L}")
        # VXLV: decode voxels
        xo = self.sec["VXLV"][0]
        index = {tuple(x): k for k, x in enumerate(c.tolist())}
        vox = np.zeros(self.L, np.int64)
        prev, short_possible = 0, 0
        clist = c.tolist()
        for j, (kind, val, at) in enumerate(self.vxlv_items):
            bo = int(self.vxlv_st[at])
            if kind == 1:
                need(val <= 27, xo, f"VXLV: inflated byte {bo}: voxline {j}: code {val} > 27")
                need(self.nvox > 0, xo, f"VXLV: voxline {j}: a step with no voxels")
                u = val - 1
                base = clist[prev]
                tgt = (base[0] + u % 3 - 1, base[1] + u // 3 % 3 - 1, base[2] + u // 9 - 1)
                k = index.get(tgt)
                need(k is not None, xo, f"VXLV: inflated byte {bo}: voxline {j}: step to {tgt}, not in the voxel table")
            else:
                dz = int(val)
                k = prev + ((dz >> 1) ^ -(dz & 1))
                need(0 <= k < self.nvox, xo, f"VXLV: inflated byte {bo}: voxline {j}: voxel {k} outside 0 … {self.nvox - 1}")
                if self.nvox and max(abs(a - b) for a, b in zip(clist[k], clist[prev])) <= 1:
                    short_possible += 1
            vox[j] = k
            prev = k
        if short_possible:
            self.notes.append(f"VXLV: {short_possible} long form(s) where the short form applies (§4.4: writers use the short)")
        self.vox = vox
        # VXLC
        co = self.sec["VXLC"][0]
        need((self.vxlc >> np.uint64(32)).max(initial=0) == 0, co, "VXLC: own point count ≥ 2^31")
        own = (self.vxlc >> np.uint64(1)).astype(np.int64)
        syn = (self.vxlc & np.uint64(1)).astype(bool)
        i = first(own < 1)
        need(i is None, co, f"VXLC: voxline {i}: own point count 0")
        strm = np.r_[0, np.cumsum(self.strl)]
        self.strm = strm
        nonempty = np.diff(strm) > 0
        firstv = np.zeros(self.L, bool)
        firstv[strm[:-1][nonempty]] = True
        last = np.zeros(self.L, bool)
        last[strm[1:][nonempty] - 1] = True
        i = first(syn & firstv)
        need(i is None, co, f"VXLC: voxline {i}: the first voxline of a streamline is marked synthetic")
        cj = (~last).astype(np.int64)
        vcount = np.bincount(vox, weights=own + cj, minlength=self.nvox).astype(np.int64)
        scount = np.bincount(vox, weights=own + cj - 1, minlength=self.nvox).astype(np.int64)
        i = first((vcount < 1) | (vcount >= 2**32))
        need(i is None, vo, f"voxel {i} gets {vcount[i] if i is not None else 0} vertices, expected 1 … 2^32 − 1")
        mo = self.sec["META"][0]
        for nm, got, want, at in (("vertex_count", vcount.sum(), self.V, 16), ("segment_count", scount.sum(), self.S, 24),
                                  ("point_count", own.sum() - syn.sum(), self.P, 8),
                                  ("synthetic_point_count", syn.sum(), self.synth, 40)):
            need(int(got) == want, mo + at, f"the streams give {nm} {int(got)}, META says {want}")
        need(int(own.sum()) == self.n, self.sec["PACK"][0] + 48, f"Σ own = {own.sum()}, PACK.point_count n = {self.n}")
        self.own, self.syn, self.firstv, self.last, self.cj = own, syn, firstv, last, cj
        self.vcount, self.scount = vcount, scount
        self.sid = np.repeat(np.arange(self.N), np.diff(strm))
        # groups (§4.6)
        if hasattr(self, "groups"):
            go = self.sec["GRPS"][0]
            for g, (name, mem, at) in enumerate(self.groups):
                need(b"\0" not in name, go, f"GRPS: inflated byte {at}: group {g}'s name holds a NUL")
                need(not mem or mem[-1] < self.N, go, f"GRPS: group {g}: member {mem[-1] if mem else 0} ≥ streamline_count {self.N}")
                try:
                    name.decode("utf-8")
                except UnicodeDecodeError:     # the .vxl requires it (§5.9, §7 step 3); §8 does not list it
                    self.notes.append(f"GRPS group {g}: name not valid UTF-8")
        # PVAL / SVAL (§4.7), all before any stream is inflated
        self.valsets = {}
        for name, cnt in (("PVAL", self.n), ("SVAL", self.N)):
            if name in self.sec:
                self.valsets[name] = self.parse_values(name, cnt)
        # GDAT: .vxl §5.13 against the package's group count
        if "GDAT" in self.raw:
            g = vr.VxlFile("GDAT", None, data=self.raw["GDAT"])
            g.sections = {"GDAT": (0, len(self.raw["GDAT"]), 0)}
            try:
                self.gdat_count = g.check_gdat(len(self.groups) if hasattr(self, "groups") else 0)
            except vr.Invalid as e:
                fail(self.sec["GDAT"][0], f"GDAT (inflated): {e}")

    def parse_values(self, name, n):
        off, p = self.payload(name)
        need(len(p) >= 16, off, f"{name}: {len(p)} bytes, shorter than its 16-byte header")
        m, res, cnt = struct.unpack_from("<IIQ", p)
        need(1 <= m <= 64, off, f"{name}: set_count {m}, expected 1 … 64")
        need(res == 0, off + 4, f"{name}: reserved {res}, expected 0")
        need(cnt == n, off + 8, f"{name}: value_count {cnt}, expected {n}")
        need(len(p) >= 16 + 64 * m, off, f"{name}: {m} entries do not fit in {len(p)} bytes")
        ents, pos = [], 16 + 64 * m
        for k in range(m):
            e = 16 + 64 * k
            nm = p[e:e + 48]
            coding, r2, ss = struct.unpack_from("<IIQ", p, e + 48)
            need(0 in nm, off + e, f"{name} set {k}: name without NUL")
            txt, rest = nm.split(b"\0", 1)
            need(not any(rest), off + e, f"{name} set {k}: name not zero after its NUL")
            need(r2 == 0, off + e + 52, f"{name} set {k}: reserved {r2}, expected 0")
            need(coding in (0, 1), off + e + 48, f"{name} set {k}: coding {coding}, this reader knows 0 and 1", "unsupported")
            need(ss <= len(p) - pos, off + e + 56, f"{name} set {k}: stream_size {ss} runs past the section")
            need(ss >= 8, off + pos, f"{name} set {k}: stream of {ss} bytes, shorter than its raw_size")
            rs = struct.unpack_from("<Q", p, pos)[0]
            need(rs == 4 * n, off + pos, f"{name} set {k}: raw_size {rs}, expected 4 n = {4 * n}")
            try:
                txt.decode("utf-8")
            except UnicodeDecodeError:
                self.notes.append(f"{name} set {k}: name not valid UTF-8 (the .vxl needs it, §8 does not say)")
            ents.append((nm, coding, pos, ss))
            pos += ss
        need(pos == len(p), off + pos, f"{name}: streams end at {pos}, the section at {len(p)}")
        sets = []
        for k, (nm, coding, pos, ss) in enumerate(ents):
            raw = self.inflate(name, off + pos, p[pos:pos + ss], f"{name} set {k}")
            if coding == 0:
                bits = np.frombuffer(raw, "<u4").copy()
            else:
                planes = np.frombuffer(raw, np.uint8).reshape(4, n).astype(np.uint32)
                dlt = planes[0] | planes[1] << 8 | planes[2] << 16 | planes[3] << 24
                bits = np.bitwise_xor.accumulate(dlt) if n else dlt
            sets.append((nm, coding, bits.astype(np.uint32)))
        return sets

    # ---------------- step 7: positions ----------------
    def draco(self, buf, where, at, count, comps):
        """§8 step 7: the header must name a point cloud, sequential encoding, no metadata, and its int32
        point count (byte 11) the expected one, before the buffer goes to Draco; then §5.3's checks."""
        need(len(buf) >= 15, at, f"{where}: Draco buffer of {len(buf)} bytes, shorter than header and count")
        need(buf[:5] == b"DRACO", at, f"{where}: no DRACO magic")
        vmaj, vmin, etype, meth, flags = struct.unpack_from("<BBBBH", buf, 5)
        need(etype == 0, at + 7, f"{where}: Draco encoder type {etype}, expected 0 (point cloud)")
        need(meth == 0, at + 8, f"{where}: Draco method {meth}, expected 0 (sequential)")
        need(not flags & 0x8000, at + 9, f"{where}: Draco metadata flag set")
        cnt = struct.unpack_from("<i", buf, 11)[0]
        need(cnt == count, at + 11, f"{where}: Draco point count {cnt}, expected {count}")
        if (vmaj, vmin) != (2, 3):     # §5.3: the version is Draco's to accept; a note
            self.notes.append(f"{where}: Draco bitstream {vmaj}.{vmin}, §1 names 2.3")
        r = subprocess.run([self.dump, "-"], input=buf, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        need(r.returncode == 0, at, f"{where}: Draco refuses it: {r.stderr.decode(errors='replace').strip()}")
        out = r.stdout
        npts, nat = struct.unpack_from("<II", out)
        need(npts == count, at, f"{where}: decodes to {npts} points, expected {count}")
        need(nat == 1, at, f"{where}: {nat} attributes, expected 1")
        atype, dtype, nc = struct.unpack_from("<III", out, 8)
        need(dtype == 5 and nc == comps, at, f"{where}: attribute of data type {dtype} × {nc}, expected int32 (5) × {comps}")
        if atype != 4:
            self.notes.append(f"{where}: attribute type {atype}, §5.3 says GENERIC (4)")
        need(len(out) == 20 + 4 * npts * nc, at, f"{where}: dump program output of wrong size")
        return np.frombuffer(out, "<i4", npts * nc, 20).reshape(npts, nc)

    def step7(self):
        n, C, t, b = self.n, self.C, self.t, self.b
        # shipping order (§5.1): streamlines by depth Λ−1 … 0 (predictor 2), else 0, 1, 2 …
        cnt = np.bincount(self.sid, weights=self.own, minlength=self.N).astype(np.int64) if self.N else np.zeros(0, np.int64)
        self.cnt = cnt
        dep = vr.depths(self.N, self.plc) if self.pred == 2 else np.zeros(self.N, np.int64)
        ship = np.lexsort((np.arange(self.N), -dep)) if self.N else np.zeros(0, np.int64)
        sstart = np.zeros(self.N, np.int64)
        sstart[ship] = np.cumsum(cnt[ship]) - cnt[ship]
        vstart = np.cumsum(cnt) - cnt
        # for each shipped point i: its streamline and its index within it
        inpos = np.arange(n) - np.repeat(sstart[ship], cnt[ship])
        ipos = np.arange(n)
        h = np.minimum(inpos, ipos % C)       # earlier points of the same chunk and the same streamline
        # decode chunks: residuals
        r = np.zeros((n, 3), np.int64)
        self.escapes = 0
        for ch in range(self.nch):
            lo, hi = ch * C, min(n, (ch + 1) * C)
            ssz, esz = int(self.chnk[ch][0]), int(self.chnk[ch][1])
            at = int(self.chunk_at[ch])
            sym = self.draco(self.data[at:at + ssz], f"chunk {ch} symbol cloud", at, hi - lo, 1)[:, 0].astype(np.int64)
            i = first((sym < 0) | (sym > 2**(3 * t)))
            need(i is None, at, f"chunk {ch}: symbol {sym[i] if i is not None else 0} of point {lo + (i or 0)} outside [0, 2^3t = {2**(3 * t)}]")
            esc = sym == 0
            u = sym - 1
            z = np.stack([u % 2**t, (u >> t) % 2**t, u >> (2 * t)], 1)
            rr = (z >> 1) ^ -(z & 1)
            ne = int(esc.sum())
            if ne == 0:
                need(esz == 0, self.sec["CHNK"][0] + 16 * ch + 8, f"chunk {ch}: no escapes but an escape buffer of {esz} bytes")
            else:
                need(esz > 0, self.sec["CHNK"][0] + 16 * ch + 8, f"chunk {ch}: {ne} escapes but no escape buffer")
                self.escapes += ne
                rr[esc] = self.draco(self.data[at + ssz:at + ssz + esz], f"chunk {ch} escape cloud", at + ssz, ne, 3)
                ze = (rr[esc] << 1) ^ (rr[esc] >> 31)                   # 32-bit zigzag of the escaped triplets
                m = int((ze < 2**t).all(1).sum())
                if m:   # §5.3: writers escape exactly the points without a symbol; readers accept more
                    self.notes.append(f"chunk {ch}: {m} escaped point(s) had a joint symbol")
            r[lo:hi] = rr
        # prediction (§5.2): δ_i = k_i − k_{i−1} (k_{−1} = 0 at a chunk start); δ = r where h ≤ 1, else δ_{i−1} + r
        seg_start = h <= 1
        cs = np.cumsum(r, 0)
        base = np.maximum.accumulate(np.where(seg_start, ipos, 0)) if n else ipos
        delta = cs - (cs[base] - r[base])
        # k = cumsum of δ within the chunk
        k = np.empty_like(delta)
        for ch in range(self.nch):
            lo, hi = ch * C, min(n, (ch + 1) * C)
            k[lo:hi] = np.cumsum(delta[lo:hi], 0)
        i = first(((k < 0) | (k > 2**b - 1)).any(1))
        need(i is None, int(self.chunk_at[i // C]) if i is not None else 0,
             f"chunk {(i or 0) // C}: point {i} decodes to quanta {k[i] if i is not None else 0}, outside [0, 2^b − 1 = {2**b - 1}]")
        self.k = k
        # §6: x = f32(o_c + double(k)·q), binary64 multiply then add (numpy does not fuse), then to f32
        x = (self.o + k.astype(np.float64) * self.q).astype(np.float32)
        # back to VXLN order: VXLN-order point p of streamline j is shipped point sstart[j] + (p − vstart[j])
        sid_p = np.repeat(np.arange(self.N), cnt)
        vx = sstart[sid_p] + (np.arange(n) - vstart[sid_p])
        self.pts = x[vx]                      # decoded points in VXLN order (own points of every voxline)
        self.kq = k[vx]

    def validate(self):
        self.step1()
        self.step2()
        self.step3()
        self.step4()
        self.step5()
        self.step6()
        self.step7()

    # ---------------- §7 rebuild ----------------
    def rebuild(self, levels, encoding):
        """The .vxl content of §7 for a file of `levels` (META.level_count: 0 or 2 … 8) and position
        encoding (0 float32, 1 packed). Returns a dict of arrays / bytes."""
        out = {}
        lc = levels if self.P > 0 else 0               # .vxl §5.1: a file of no points has no levels
        nlev = max(lc, 1)
        L, V = self.L, self.V
        dep = vr.depths(self.N, lc)[self.sid] if L else np.zeros(0, np.int64)
        size = self.own + self.cj
        # blocks: per voxel, voxlines by depth, deepest first, then in VXLN order (.vxl §5.4, §5.6)
        order = np.lexsort((np.arange(L), -dep, self.vox)) if L else np.zeros(0, np.int64)
        start = np.empty(L, np.int64)
        start[order] = np.cumsum(size[order]) - size[order]
        vfirst = np.cumsum(self.vcount) - self.vcount
        # VERT (§7 step 4): own decoded points, then a copy of the next voxline's first decoded point
        pstart = np.cumsum(self.own) - self.own     # VXLN-order index of each voxline's first own point
        verts = np.empty((V, 3), np.float32)
        tgt = np.repeat(start, self.own) + (np.arange(self.n) - np.repeat(pstart, self.own))
        verts[tgt] = self.pts
        nl = np.nonzero(self.cj)[0]
        verts[start[nl] + self.own[nl]] = self.pts[pstart[nl + 1]]
        vox_of = np.repeat(np.arange(self.nvox), self.vcount)
        tmin = np.full((self.nvox, 3), np.inf, np.float32)
        tmax = np.full((self.nvox, 3), -np.inf, np.float32)
        np.minimum.at(tmin, vox_of, verts)
        np.maximum.at(tmax, vox_of, verts)
        tmin, tmax = tmin + np.float32(0), tmax + np.float32(0)     # a zero written as +0 (.vxl §5.3)
        endv = np.zeros(V, bool)
        endv[start + size - 1] = True
        out.update(verts=verts, tmin=tmin, tmax=tmax, start=start, endv=endv, vox_of=vox_of)
        if encoding == 1:
            q = vr.pack_q(verts, tmin[vox_of], tmax[vox_of])
            out["words"] = (q[:, 0] | q[:, 1] << 10 | q[:, 2] << 20 | endv.astype(np.int64) << 30).astype(np.uint32)
        # LODS: v_d, n_d = vertices / segments of the voxlines of depth ≥ d (.vxl §5.12)
        vl = np.zeros((self.nvox, nlev), np.int64)
        nl_ = np.zeros((self.nvox, nlev), np.int64)
        for d in range(nlev):
            sel = dep >= d
            vl[:, d] = np.bincount(self.vox[sel], weights=size[sel], minlength=self.nvox)
            nl_[:, d] = np.bincount(self.vox[sel], weights=size[sel] - 1, minlength=self.nvox)
        out["lods"], out["lods_n"] = vl, nl_
        # VOXT (§7 step 3)
        bits = np.maximum(1, np.frexp((vl - 1).astype(np.float64))[1]).astype(np.int64)   # ORDB, .vxl §5.5
        lvl_bytes = (self.K * ((nl_ * bits + 7) // 8) + 3) // 4 * 4
        obytes = lvl_bytes.sum(1)
        vt = np.zeros(self.nvox, vr.VOXT_DT)
        vt["coord"] = self.coord
        vt["flags"] = np.where(self.vcount <= 65536, 0, np.where(self.vcount <= 2**24, 1, 2))
        vt["tmin"], vt["tmax"] = tmin, tmax
        vt["vfirst"], vt["vcount"], vt["scount"] = vfirst, self.vcount, self.scount
        vt["ooff"] = np.cumsum(obytes) - obytes
        out["voxt"], out["ordb_size"] = vt, int(obytes.sum())
        # META (§7 step 1)
        m = bytearray(self.meta_raw)
        bmin = verts.astype(np.float64).min(0) + 0.0 if V else np.zeros(3)
        bmax = verts.astype(np.float64).max(0) + 0.0 if V else np.zeros(3)
        struct.pack_into("<3d3dII", m, 104, *bmin, *bmax, encoding, lc)
        out["meta"], out["bmin"], out["bmax"] = bytes(m), bmin, bmax
        out["dirs"] = self.dirs_raw
        # STRM, VXLN (§7 step 2)
        out["strm"] = self.strm.astype(np.uint64)
        out["vxln"] = np.stack([self.vox, self.own | self.syn.astype(np.int64) << 31], 1).astype(np.uint32)
        # SLEN (§7 step 5): from each streamline's decoded points, synthetic ones left out
        first_pt = np.zeros(self.n, bool)
        first_pt[pstart] = True
        real = ~(first_pt & np.repeat(self.syn, self.own))
        rc = np.bincount(self.sid[np.repeat(np.arange(L), self.own)][real], minlength=self.N) if L else np.zeros(self.N, np.int64)
        out["slen"] = vr.VxlFile.lengths(None, self.pts[real], rc).astype(np.float32) if self.N else np.zeros(0, np.float32)
        out["counts"] = rc
        # PROV (§7 step 6)
        prov = {}
        if "PROV" in self.raw:
            try:
                prov = json.loads(self.raw["PROV"].decode("utf-8"))
            except (UnicodeDecodeError, ValueError) as e:
                fail(self.sec["PROV"][0], f"PROV is not UTF-8 JSON: {e}")
            need(isinstance(prov, dict), self.sec["PROV"][0], "PROV is not a JSON object (§7 step 6)")
        # §7 step 6: the package's file name without its directory
        prov["vxlz"] = {"package": os.path.basename(self.path), "bits": self.b, "quantum_mm": self.q,
                        "range_mm": self.R, "error_bound_mm": self.eb, "max_error_mm": self.maxe,
                        "rms_error_mm": self.rmse}
        out["prov"] = prov
        # GRPS (§7 step 7) re-encoded by .vxl §5.9
        if hasattr(self, "groups"):
            g = bytearray(struct.pack("<II", len(self.groups), 0))
            for name, mem, _ in self.groups:
                g += struct.pack("<I", len(name)) + name
                g += bytes(vr.align(len(g), 8) - len(g))
                g += struct.pack("<Q", len(mem)) + np.array(mem, np.uint64).astype("<u8").tobytes()
            out["grps"] = bytes(g)
        if "GDAT" in self.raw:
            out["gdat"] = self.raw["GDAT"]
        # VVAL / SVAL (§7 step 8), laid out by .vxl §5.11
        for pk, vk, cnt in (("PVAL", "VVAL", V), ("SVAL", "SVAL", self.N)):
            if pk not in self.valsets:
                continue
            sets = self.valsets[pk]
            mm = len(sets)
            D, stride = vr.align(16 + 64 * mm, 64), vr.align(4 * cnt, 64)
            buf = bytearray(D + mm * stride)
            struct.pack_into("<IIQ", buf, 0, mm, 0, cnt)
            for k, (nm, coding, bits) in enumerate(sets):
                if pk == "PVAL":
                    a = np.empty(V, np.uint32)
                    a[tgt] = bits
                    a[start[nl] + self.own[nl]] = bits[pstart[nl + 1]]
                else:
                    a = bits
                f = a.view(np.float32)
                fin = f[np.isfinite(f)]
                lo, hi = (fin.min(), fin.max()) if len(fin) else (np.float32(np.nan), np.float32(np.nan))
                buf[16 + 64 * k:16 + 64 * k + 48] = nm
                struct.pack_into("<ff", buf, 16 + 64 * k + 48, lo, hi)
                buf[D + k * stride:D + k * stride + 4 * cnt] = a.astype("<u4").tobytes()
            out[vk.lower()] = bytes(buf)
        return out


# ---------------- --compare ----------------
def compare(pkg, path, say):
    f = vr.VxlFile(path, say)
    try:
        f.check_all()
    except vr.Invalid as e:
        raise Different(f"{path} fails the .vxl reader's checks (.vxl §7): {e}")
    diffs, notes = [], []
    # §7 step 1: the unpacker chooses Λ; rebuilt with the unpacked file's to compare the rest
    rb = pkg.rebuild(f.lc, f.pos_enc)

    def sec(name):
        if name not in f.sections:
            return None
        o, s = f.sec(name)
        return f.data[o:o + s]

    def eq(name, got, want, what=""):
        if got is None and want is None:
            return
        if got is None or want is None:
            diffs.append(f"{name}: {'missing in the file' if got is None else 'present in the file, §7 gives none'}")
            return
        if isinstance(got, bytes) and isinstance(want, bytes):
            if got != want:
                i = next((k for k in range(min(len(got), len(want))) if got[k] != want[k]), min(len(got), len(want)))
                o = f.sec(name)[0] if name in f.sections else 0
                diffs.append(f"{name}: byte {o + i} (payload byte {i}) differs{what} (sizes {len(got)} / {len(want)})")
            return
        if got.shape != want.shape or not np.array_equal(got, want):
            diffs.append(f"{name}: differs{what}")

    # META: every byte the spec determines
    meta = sec("META")
    want = bytearray(rb["meta"])
    want[152:156] = struct.pack("<I", f.pos_enc)     # the chosen encoding
    eq("META", meta, bytes(want))
    eq("DIRS", sec("DIRS"), rb["dirs"])
    eq("STRM", sec("STRM"), rb["strm"].astype("<u8").tobytes())
    eq("VXLN", sec("VXLN"), rb["vxln"].astype("<u4").tobytes())
    eq("VOXT", sec("VOXT"), rb["voxt"].tobytes())
    if f.lc >= 2:
        lods = np.stack([rb["lods"][:, 1:], rb["lods_n"][:, 1:]], 2).astype("<u4").tobytes()
        eq("LODS", sec("LODS"), lods)
    if f.pos_enc == 0:
        eq("VERT", sec("VERT"), rb["verts"].astype("<f4").tobytes(), " (float32 vertices, bit for bit)")
    else:
        eq("VERT", sec("VERT"), rb["words"].astype("<u4").tobytes(), " (packed words, .vxl §5.4 of the decoded vertices)")
    if "ORDB" in f.sections and f.sec("ORDB")[1] != rb["ordb_size"]:
        diffs.append(f"ORDB: size {f.sec('ORDB')[1]}, .vxl §5.5 gives {rb['ordb_size']}")
    eq("SLEN", sec("SLEN"), rb["slen"].astype("<f4").tobytes() if pkg.N else None, " (lengths of the decoded points)")
    eq("GRPS", sec("GRPS"), rb.get("grps"))
    eq("GDAT", sec("GDAT"), rb.get("gdat"))
    eq("VVAL", sec("VVAL"), rb.get("vval"))
    eq("SVAL", sec("SVAL"), rb.get("sval"))
    # PROV: the JSON object, numbers compared as numbers; and its bytes as .vxl §5.8 serialises
    pv = sec("PROV")
    if pv is None:
        diffs.append("PROV missing in the unpacked file (§7 step 6 always writes one)")
    else:
        got = json.loads(pv.decode("utf-8"))
        if got != rb["prov"]:
            keys = sorted(set(got) | set(rb["prov"]))
            bad = [k for k in keys if got.get(k) != rb["prov"].get(k)]
            detail = "; ".join(f"{k}: file {json.dumps(got.get(k))[:300]} vs §7 {json.dumps(rb['prov'].get(k))[:300]}" for k in bad)
            diffs.append(f"PROV differs: {detail}")
        ser = json.dumps(rb["prov"], separators=(",", ":"), sort_keys=True, ensure_ascii=False).encode()
        if ser != pv:
            notes.append("PROV bytes differ from Python's serialisation of the same object (number formatting / "
                         "key order not fixed by the spec): " + pv.decode()[-200:])
    for n_ in f.notes:
        notes.append(f".vxl reader note: {n_}")
    return f, diffs, notes


def find_dump(arg):
    if arg:
        return arg
    if os.environ.get("VXLZ_DRACO_DUMP"):
        return os.environ["VXLZ_DRACO_DUMP"]
    src = os.path.join(REPO, "tests", "spec", "draco_cloud_dump.cpp")
    h = hashlib.sha256(open(src, "rb").read()).hexdigest()[:16]
    exe = os.path.join(tempfile.gettempdir(), f"draco_cloud_dump-{h}")
    if not os.path.exists(exe):
        tmp = exe + f".{os.getpid()}"
        r = subprocess.run(["g++", "-std=c++20", "-O2", src, "-ldraco", "-o", tmp], capture_output=True, text=True)
        if r.returncode != 0:
            raise OSError(f"cannot build {src}: {r.stderr[-300:]}")
        os.replace(tmp, exe)
    return exe


def main():
    def add_arguments(ap):
        ap.add_argument("file", metavar="PACKAGE.vxlz")
        ap.add_argument("--compare", metavar="UNPACKED.vxl", help="a .vxl that `voxlines unpack` made of the package")
        ap.add_argument("--draco-dump", metavar="PATH", help="the built tests/spec/draco_cloud_dump program")
    parsed = vr.parse_command_line(__doc__.split("\n")[0], "vxlz_spec_reader.py PACKAGE.vxlz [--compare "
                                   "UNPACKED.vxl] [--draco-dump PATH] [-q]", add_arguments)
    if parsed is None:
        return 2
    a, say = parsed
    a.package = a.file
    try:
        dump = find_dump(a.draco_dump)
    except OSError as e:
        print(f"usage error: {e}", file=sys.stderr)
        return 2
    if not os.access(dump, os.X_OK):
        print(f"usage error: {dump}: not an executable", file=sys.stderr)
        return 2
    vr.self_test_depths()
    pk = Package(a.package, say, dump)
    try:
        pk.validate()
        rb = pk.rebuild(pk.plc if pk.pred == 2 else 0, 0)  # §7 step 1: the levels the packed file had
        say(f"{a.package}: vxlz {pk.major}.{pk.minor}, sections " + " ".join(f"{k}:{v[1]}" for k, v in pk.sec.items()))
        say(f"  N={pk.N} P={pk.P} V={pk.V} S={pk.S} L={pk.L} synthetic={pk.synth} voxels={pk.nvox} n={pk.n}")
        say(f"  b={pk.b} predictor={pk.pred} levels={pk.plc} q={pk.q:.6g} R={pk.R:.6g} C={pk.C} chunks={pk.nch} "
            f"t={pk.t} error_bound={pk.eb:.6g} (max {pk.maxe:.6g}, rms {pk.rmse:.6g}); {pk.escapes} escaped point(s)")
        for k, sets in pk.valsets.items():
            say(f"  {k}: " + ", ".join(f"{nm.rstrip(bytes(1)).decode(errors='replace')!r} coding {c}" for nm, c, _ in sets))
        if hasattr(pk, "groups"):
            say(f"  GRPS: {len(pk.groups)} group(s), {sum(len(m) for _, m, _ in pk.groups)} members; "
                f"GDAT: {getattr(pk, 'gdat_count', 0)} row(s)")
        say(f"  rebuilt: bounds {rb['bmin'].tolist()} … {rb['bmax'].tolist()}, ORDB {rb['ordb_size']} bytes, "
            f"groups {len(pk.groups) if hasattr(pk, 'groups') else 0}, value sets "
            f"{ {k: len(v) for k, v in pk.valsets.items()} }")
        diffs = []
        if a.compare:
            f, diffs, cnotes = compare(pk, a.compare, say)
            for n_ in cnotes:
                say(f"  compare note: {n_}")
            for d in diffs:
                say(f"  DIFFERENT: {d}")
            if not diffs:
                say(f"  compare: {a.compare} equals the rebuild ({'float32 bit for bit' if f.pos_enc == 0 else 'packed words'}"
                    f", META/DIRS/VOXT{'/LODS' if f.lc >= 2 else ''}/STRM/VXLN/SLEN/PROV/GRPS/GDAT/VVAL/SVAL; ORDB sorted by "
                    f".vxl §6.4 from those vertices, checked by the .vxl reader)")
        for n_ in pk.notes:
            say(f"  note: {n_}")
    except Invalid as e:
        print(f"{a.package}: {'UNSUPPORTED' if e.kind == 'unsupported' else 'INVALID'}: {e}", file=sys.stderr)
        return 1
    except Different as e:
        print(f"{a.package}: DIFFERENT: {e}", file=sys.stderr)
        return 1
    except (ValueError, IndexError, OverflowError, MemoryError, KeyError, struct.error) as e:
        print(f"{a.package}: INVALID (not readable as the spec describes: {type(e).__name__}: {e})", file=sys.stderr)
        return 1
    if diffs:
        print(f"{a.package}: DIFFERENT from {a.compare}: {diffs[0]}" + (f" (+{len(diffs) - 1} more)" if len(diffs) > 1 else ""))
        return 1
    print(f"{a.package}: OK ({pk.nvox} voxels, {pk.n} shipped points, {pk.nch} chunk(s)"
          f"{', equals ' + a.compare if a.compare else ''}{f', {len(pk.notes)} note(s)' if pk.notes else ''})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
