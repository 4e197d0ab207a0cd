#!/usr/bin/python3
"""A synthetic T1-like head for the README's picture of voxview --image (there is no real T1 among the
fixtures): an ellipsoid scalp, a dark skull, grey matter, a brighter inner "white matter", dark ventricles,
slight noise. 1.5 mm voxels, int16 with scl_slope 0.5 (so that the picture also shows the scaling), placed
around the `voxlines synth` tractogram (which spans about x -62..62, y -89..57, z -42..63 mm).

Usage: /usr/bin/python3 scripts/synth_head.py OUT.nii.gz
"""
import sys

import nibabel as nib
import numpy as np

out = sys.argv[1]
step = 1.5
shape = (120, 150, 124)
origin = np.array([-89.25, -128.25, -81.75])  # RAS mm of voxel (0, 0, 0)
affine = np.diag([step, step, step, 1.0])
affine[:3, 3] = origin

i, j, k = np.meshgrid(*(np.arange(n) for n in shape), indexing="ij")
x, y, z = (origin[a] + step * idx for a, idx in enumerate((i, j, k)))
centre = np.array([0.0, -16.0, 10.0])


def inside(semi, shift=(0.0, 0.0, 0.0)):
    c = centre + np.array(shift)
    return ((x - c[0]) / semi[0]) ** 2 + ((y - c[1]) / semi[1]) ** 2 + ((z - c[2]) / semi[2]) ** 2 <= 1.0


t1 = np.zeros(shape, np.float32)
t1[inside((84, 110, 88))] = 500   # scalp
t1[inside((79, 105, 83))] = 120   # skull
t1[inside((75, 101, 79))] = 250   # CSF
t1[inside((72, 98, 76))] = 620    # grey matter
t1[inside((58, 84, 60))] = 900    # white matter
for side in (-1, 1):              # lateral ventricles
    t1[inside((7, 30, 10), (side * 10.0, 5.0, 8.0))] = 200
rng = np.random.default_rng(1)
t1[t1 > 0] += rng.normal(0, 25, int((t1 > 0).sum()))
stored = np.clip(np.round(t1 / 0.5), 0, 32767).astype(np.int16)

img = nib.Nifti1Image(stored, affine)
img.header.set_slope_inter(0.5, 0)
img.header.set_sform(affine, code=1)
img.header.set_qform(affine, code=1)
nib.save(img, out)
