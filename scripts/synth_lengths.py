#!/usr/bin/python3
"""A whole-brain-like TCK whose streamlines differ from `voxlines synth`'s in length and step: lengths drawn from a
log-normal distribution (median 28 mm, many short ones and a tail to 200 mm, as probabilistic tracking gives),
0.75 mm steps, directions following a smooth field with a little noise per streamline, every streamline kept inside
the same brain-sized ellipsoid. It is for benchmarks that must not be tuned to one generator's streamlines (a region
dragged through the window, conversion): the same seed gives the same bytes.

Usage: /usr/bin/python3 scripts/synth_lengths.py OUT.tck [--streamlines N] [--seed S]
"""
import argparse
import os
import sys

import numpy as np

CENTRE = np.array([0.0, -16.0, 10.0], dtype=np.float32)
SEMI_AXES = np.array([62.0, 73.0, 52.0], dtype=np.float32)
STEP_MM = 0.75
MEDIAN_MM, SIGMA, MIN_MM, MAX_MM = 28.0, 0.7, 4.0, 200.0
CHUNK = 40000


def field(p, phases):
    """A smooth direction field: three sums of sines over the position, one per axis."""
    d = np.empty_like(p)
    for axis in range(3):
        a, b, c = phases[axis]
        d[:, axis] = (np.sin(p[:, (axis + 1) % 3] / 17.0 + a) + np.sin(p[:, (axis + 2) % 3] / 23.0 + b)
                      + 0.5 * np.sin(p[:, axis] / 31.0 + c))
    return d


def inside(p):
    return (((p - CENTRE) / SEMI_AXES) ** 2).sum(axis=1) <= 1.0


def chunk_points(rng, n, phases):
    """n streamlines as one float32 array of points, each followed by a NaN separator row."""
    lengths = np.clip(rng.lognormal(np.log(MEDIAN_MM), SIGMA, n), MIN_MM, MAX_MM)
    counts = np.maximum(2, np.round(lengths / STEP_MM).astype(np.int64) + 1)
    most = int(counts.max())
    # Seeds uniform in the inner part of the ellipsoid.
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    seeds = CENTRE + 0.85 * SEMI_AXES * u * rng.random((n, 1)) ** (1 / 3)
    sign = np.where(rng.random((n, 1)) < 0.5, -1.0, 1.0).astype(np.float32)
    jitter = rng.normal(scale=0.35, size=(n, 3)).astype(np.float32)
    points = np.full((n, most + 1, 3), np.nan, dtype=np.float32)
    p = seeds.astype(np.float32)
    alive = np.ones(n, dtype=bool)
    ends = counts.copy()
    heading = None
    for k in range(most):
        points[alive, k] = p[alive]
        d = sign * field(p, phases) + jitter
        d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-6)
        if heading is not None:  # no sharp turns: blend with the last heading
            d = 0.7 * heading + 0.3 * d
            d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-6)
        heading = d
        p = p + STEP_MM * d
        leaving = alive & ~inside(p)
        ends[leaving] = np.minimum(ends[leaving], k + 1)
        alive &= ~leaving & (k + 1 < counts)
    ends = np.maximum(ends, 2)
    keep = np.arange(most + 1)[None, :] <= ends[:, None]
    points[np.arange(n), ends] = np.nan  # the separator after each streamline
    return points[keep]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out")
    parser.add_argument("--streamlines", type=int, default=1000000)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    phases = rng.uniform(0, 2 * np.pi, size=(3, 3))
    header = "mrtrix tracks\ndatatype: Float32LE\ncount: {:d}\nstep_size: {}\nfile: . {:d}\nEND\n"
    offset = 0
    text = header.format(args.streamlines, STEP_MM, offset)
    while len(text) != offset:  # the offset's own digits are in the header
        offset = len(text)
        text = header.format(args.streamlines, STEP_MM, offset)
    temporary = args.out + ".partial"
    points = 0
    with open(temporary, "wb") as out:
        out.write(text.encode())
        done = 0
        while done < args.streamlines:
            n = min(CHUNK, args.streamlines - done)
            block = chunk_points(rng, n, phases)
            out.write(block.astype("<f4").tobytes())
            points += len(block) - n
            done += n
            print(f"\r{done}/{args.streamlines} streamlines", end="", file=sys.stderr, flush=True)
        out.write(np.full(3, np.inf, dtype="<f4").tobytes())
    os.replace(temporary, args.out)
    print(f"\n{args.out}: {args.streamlines} streamlines, {points} points", file=sys.stderr)


if __name__ == "__main__":
    main()
