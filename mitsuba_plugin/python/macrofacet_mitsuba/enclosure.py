"""The boundary of a mesh mean surface: a closed triangle mesh around the region f < level, from
the library's mf_surface_enclosure (conservative: the whole region is inside; watertight,
outward-facing; with cell size 0 the mesh's own faces moved out along its vertex normals when that
verifies, else the faces of grid cells, within one cell of the level set), written as a binary
PLY.

A macrofacet medium fills f < k sigma around its mean surface; rays enter it through the scene's
boundary shape, which must contain that region. For a sphere of radius r the boundary is the
sphere of radius r + k sigma; for a mesh it is this enclosure. The library is called through
its C ABI (ctypes on the package's libmacrofacet.so); the mesh is loaded by Mitsuba, so every
mesh format Mitsuba reads works, with Mitsuba's vertex merging.
"""
import ctypes
import math
import os
import struct

_LIB = None


class _Vec3(ctypes.Structure):
    _fields_ = [("x", ctypes.c_double), ("y", ctypes.c_double), ("z", ctypes.c_double)]


class _Mesh(ctypes.Structure):  # mf_mesh
    _fields_ = [("positions", ctypes.POINTER(ctypes.c_double)), ("vertex_count", ctypes.c_size_t),
                ("indices", ctypes.POINTER(ctypes.c_uint32)), ("triangle_count", ctypes.c_size_t),
                ("normals", ctypes.POINTER(ctypes.c_double)), ("uvs", ctypes.POINTER(ctypes.c_double))]


def _library():
    global _LIB
    if _LIB is None:
        path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "lib", "libmacrofacet.so")
        lib = ctypes.CDLL(path)
        vp = ctypes.c_void_p
        lib.mf_surface_new_mesh.argtypes = [ctypes.POINTER(_Mesh), ctypes.c_size_t, ctypes.c_double, ctypes.POINTER(vp)]
        lib.mf_surface_enclosure.argtypes = [vp, vp, ctypes.c_double, ctypes.c_double, ctypes.POINTER(vp)]
        lib.mf_enclosure_mesh.argtypes = [vp, ctypes.POINTER(_Mesh)]
        lib.mf_enclosure_free.argtypes = [vp]
        lib.mf_surface_free.argtypes = [vp]
        lib.mf_last_error_message.argtypes = [ctypes.c_char_p, ctypes.c_size_t, ctypes.POINTER(ctypes.c_size_t)]
        for f in (lib.mf_surface_new_mesh, lib.mf_surface_enclosure, lib.mf_enclosure_mesh, lib.mf_last_error_message):
            f.restype = ctypes.c_int
        lib.mf_enclosure_free.restype = lib.mf_surface_free.restype = None
        _LIB = lib
    return _LIB


def _check(status, what):
    if status != 0:
        lib = _library()
        buf = ctypes.create_string_buffer(1024)
        lib.mf_last_error_message(buf, len(buf), None)
        raise ValueError(f"{what}: {buf.value.decode('utf-8', 'replace')}")


def enclosure(positions, faces, level, cell_size=0.0):
    """The enclosure of f < level around the closed mesh (positions: 3n floats, faces: 3m vertex
    indices, counter-clockwise seen from outside). Returns (positions, faces) as lists; level in
    the mesh's units; cell_size 0 asks for the mesh's own faces moved out (else cells of 1/128 of
    the mesh's largest extent)."""
    lib = _library()
    nv, nf = len(positions) // 3, len(faces) // 3
    pos = (ctypes.c_double * (3 * nv))(*positions)
    idx = (ctypes.c_uint32 * (3 * nf))(*faces)
    desc = _Mesh(pos, nv, idx, nf, None, None)
    surface, enc = ctypes.c_void_p(), ctypes.c_void_p()
    # One per core, at most the library's MF_MAX_BUILD_THREADS (1024; more is refused); the same
    # surface whatever the count.
    threads = min(os.cpu_count() or 1, 1024)
    # The surface serves this enclosure only: built for any medium (no reach, infinity).
    _check(lib.mf_surface_new_mesh(ctypes.byref(desc), threads, math.inf, ctypes.byref(surface)),
           "the mesh is not a valid mean surface")
    try:
        _check(lib.mf_surface_enclosure(surface, None, float(level), float(cell_size), ctypes.byref(enc)),
               "mf_surface_enclosure")
        try:
            out = _Mesh()
            _check(lib.mf_enclosure_mesh(enc, ctypes.byref(out)), "mf_enclosure_mesh")
            return out.positions[:3 * out.vertex_count], out.indices[:3 * out.triangle_count]
        finally:
            lib.mf_enclosure_free(enc)
    finally:
        lib.mf_surface_free(surface)


def write_ply(filename, positions, faces):
    """A binary little-endian PLY (float32 vertices, uint32 triangles), as Mitsuba and mfrender read."""
    nv, nf = len(positions) // 3, len(faces) // 3
    header = ("ply\nformat binary_little_endian 1.0\ncomment macrofacet enclosure\n"
              f"element vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n"
              f"element face {nf}\nproperty list uchar uint vertex_indices\nend_header\n")
    with open(filename, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(struct.pack(f"<{3 * nv}f", *positions))
        tri = struct.Struct("<B3I")
        f.write(b"".join(tri.pack(3, faces[3 * i], faces[3 * i + 1], faces[3 * i + 2]) for i in range(nf)))


def load_mesh(filename):
    """(positions, faces) of a mesh file as Mitsuba loads it (obj, ply, serialized), file units."""
    import mitsuba as mi
    if mi.variant() is None:
        mi.set_variant("scalar_rgb")
    kind = os.path.splitext(filename)[1].lower().lstrip(".")
    if kind not in ("obj", "ply", "serialized"):
        raise ValueError(f"{filename}: expected an .obj, .ply or .serialized mesh")
    params = mi.traverse(mi.load_dict({"type": kind, "filename": filename}))
    return list(params["vertex_positions"]), list(params["faces"])


def write_enclosure(mesh_file, out_file, sigma, shell_extent=3.0, scale=1.0, cell_size=0.0):
    """Writes the boundary of the medium whose mean surface is `mesh_file` (in a scene where its
    to_world scales it uniformly by `scale`): the enclosure of f < shell_extent * sigma, in the
    mesh file's coordinates (give the boundary shape the mean surface's to_world). Returns the
    triangle count."""
    if not (sigma > 0 and shell_extent > 0 and scale > 0):
        raise ValueError("sigma, shell_extent and scale must be positive")
    positions, faces = load_mesh(mesh_file)
    enc_pos, enc_faces = enclosure(positions, faces, shell_extent * sigma / scale, cell_size / scale)
    write_ply(out_file, enc_pos, enc_faces)
    return len(enc_faces) // 3
