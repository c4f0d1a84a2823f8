"""Grid and texture files for the plugin's tests of spatially varying media, written with Mitsuba's
own writers (VolumeGrid, Bitmap) so that both renderers read exactly these samples:

- write_volume: a gridvolume / sdfgrid .vol file from values, x fastest;
- sphere_sdf: the unit sphere's signed distance at the nodes of a grid (an sdfgrid's convention:
  node (i, j, k) at (i, j, k) / (n - 1) of the unit cube, values in the unit cube's units);
- write_varying_media: the files of data/varying_media.xml beside a copy of it."""
import math
import os
import shutil

HERE = os.path.dirname(os.path.abspath(__file__))


def write_volume(mi, path, values, n, channels=1):
    """`values` (x fastest, `channels` per sample) on an n = (nx, ny, nz) grid as a .vol file."""
    nx, ny, nz = n
    assert len(values) == nx * ny * nz * channels
    mi.VolumeGrid(mi.TensorXf(values, (nz, ny, nx, channels))).write(path)


def sphere_sdf(n, half, radius=1.0):
    """The signed distance of the sphere of `radius` about the origin at the nodes of an n^3 grid
    over [-half, half]^3 (x fastest), in the unit cube's units (world / (2 half))."""
    out = []
    for k in range(n):
        for j in range(n):
            for i in range(n):
                x, y, z = (2 * half * c / (n - 1) - half for c in (i, j, k))
                out.append((math.sqrt(x * x + y * y + z * z) - radius) / (2 * half))
    return out


def write_varying_media(mi, work):
    """data/varying_media.xml and its files in `work`; returns the scene's path there."""
    # sigma from 0.006 to 0.03 along x (8 samples), constant along y and z
    write_volume(mi, os.path.join(work, "sigma_x.vol"), [0.006 + 0.024 * i / 7 for k in range(2) for j in range(2) for i in range(8)], (8, 2, 2))
    # the roughness along y, one period of a repeating grid
    alpha = [0.05, 0.15, 0.45, 0.2]
    write_volume(mi, os.path.join(work, "alpha_y.vol"), [alpha[j] for k in range(2) for j in range(4) for i in range(2)], (2, 4, 2))
    # a tint over uv: 16 x 8 texels in [0.35, 1]
    w, h = 16, 8
    tint = []
    for y in range(h):
        for x in range(w):
            u, v = (x + 0.5) / w, (y + 0.5) / h
            tint += [0.35 + 0.65 * u, 0.35 + 0.65 * (1 - v), 0.35 + 0.65 * (0.5 + 0.5 * math.sin(6.283 * (u + v)))]
    mi.Bitmap(mi.TensorXf(tint, (h, w, 3))).write(os.path.join(work, "tint.exr"))
    # Sigma (xx, yy, zz, xy, xz, yz) on 2^3 voxels: lengthscales^2 from 6e-4 to 5e-3 (roughness
    # sqrt(2) sigma / l from 0.2 to 0.6 at sigma 0.01), turning with x, stretched with y and z
    aniso = []
    for k in range(2):
        for j in range(2):
            for i in range(2):
                a, b, c = 6e-4 * (1 + 2 * j), 5e-3 / (1 + 2 * k), 1.5e-3
                off = 0.6 * math.sqrt(a * b) * (1 if i else -1)
                aniso += [a, b, c, off, 0.0, 0.0]
    write_volume(mi, os.path.join(work, "anisotropy.vol"), aniso, (2, 2, 2), 6)
    scene = os.path.join(work, "varying_media.xml")
    shutil.copy(os.path.join(HERE, "data", "varying_media.xml"), scene)
    return scene


def write_sdf_sphere(mi, work):
    """data/sdf_sphere.xml and its grid in `work`; returns the scene's path there."""
    write_volume(mi, os.path.join(work, "sphere_sdf.vol"), sphere_sdf(41, 1.25), (41, 41, 41))
    scene = os.path.join(work, "sdf_sphere.xml")
    shutil.copy(os.path.join(HERE, "data", "sdf_sphere.xml"), scene)
    return scene
