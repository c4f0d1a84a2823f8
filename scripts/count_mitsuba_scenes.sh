#!/usr/bin/env bash
# Count the Mitsuba 3 scenes of a folder that mfrender opens unchanged (issue 14's headline number).
#
#   scripts/count_mitsuba_scenes.sh DIR [-- MFRENDER_ARGS...]
#
# DIR holds scene files as published (e.g. mitsuba-data's tests/scenes and the tutorials' scenes,
# in their folder layout). The folder is copied to a scratch directory; the copy is never written
# back. A top-level scene is an .xml file whose root is <scene> and that no other file <include>s.
# Each is checked with `mfrender --check` (every problem of a file in one run). Public scene
# collections ship their meshes, textures and grids separately, so a referenced data file that is
# missing from the copy is replaced by a stand-in of the same format (a small sphere for .obj/.ply/
# .serialized, the .ply one with grey r, g, b per vertex and face for mesh_attribute textures; a
# grey 8x4 .exr/.png/.jpg/.bmp, a 4^3 Mitsuba .vol with 1 or 3 channels, a flat .spd) and a
# missing <path> folder is created, inside the copy only, and the check is repeated.
# Each scene is then one of:
#   opens    --check succeeds (column 'stand-ins' says how many files were stood in for)
#   refused  an unsupported plugin, parameter or element (listed: 'kind:plugin', 'plugin.parameter',
#            '<element>' or '<element attribute=...>'), also naming data files of a format no
#            stand-in exists for ('no stand-in for *.hdr')
#   other    any other problem (the first message is shown)
# Output: one tab-separated row per scene (scene, class, stand-ins this scene added to the copy --
# later scenes reuse them --, reasons), then the number of
# scenes refused for each reason, most frequent first. MFRENDER selects the binary (default:
# build/release/cpp_host/mfrender, else the first mfrender on PATH).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
[ $# -ge 1 ] || { sed -n '2,24p' "$0" >&2; exit 2; }
dir="$1"; shift
[ "${1:-}" = "--" ] && shift
[ -d "$dir" ] || { echo "count_mitsuba_scenes: no folder $dir" >&2; exit 2; }
mfrender="$(realpath -e "${MFRENDER:-$here/build/release/cpp_host/mfrender}" 2>/dev/null || true)"
[ -x "$mfrender" ] || mfrender="$(command -v mfrender || true)"
[ -x "$mfrender" ] || { echo "count_mitsuba_scenes: set MFRENDER to an mfrender binary" >&2; exit 2; }
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
cp -r "$dir/." "$work/"
exec python3 - "$work" "$mfrender" "$@" <<'PY'
import base64, collections, math, os, re, struct, subprocess, sys, zlib
import xml.etree.ElementTree as ET

work, mfrender, extra = sys.argv[1], sys.argv[2], sys.argv[3:]

# ---- stand-in data files -------------------------------------------------------------------
def sphere(nu=16, nv=8):
    """Unit UV sphere: positions, normals, uvs, triangles (closed, so it bounds a medium)."""
    pos, uv, tris = [], [], []
    for j in range(nv + 1):
        th = math.pi * j / nv
        for i in range(nu + 1):
            ph = 2 * math.pi * i / nu
            pos.append((math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)))
            uv.append((i / nu, j / nv))
    w = nu + 1
    for j in range(nv):
        for i in range(nu):
            a, b, c, d = j * w + i, j * w + i + 1, (j + 1) * w + i + 1, (j + 1) * w + i
            if j > 0: tris.append((a, c, b))
            if j < nv - 1: tris.append((a, d, c))
    return pos, pos, uv, tris

def obj_bytes():
    p, n, t, f = sphere()
    s = ''.join('v %g %g %g\n' % v for v in p) + ''.join('vn %g %g %g\n' % v for v in n)
    s += ''.join('vt %g %g\n' % v for v in t)
    s += ''.join('f %d/%d/%d %d/%d/%d %d/%d/%d\n' % tuple(k + 1 for k in (a, a, a, b, b, b, c, c, c)) for a, b, c in f)
    return s.encode()

def ply_bytes():
    """The sphere with a grey r, g, b per vertex and per face: the vertex_color and face_color
    attributes that a mesh_attribute texture may read (Mitsuba's PLY reader makes them of r, g, b)."""
    p, n, t, f = sphere()
    h = ('ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n'
         'property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n'
         'property float r\nproperty float g\nproperty float b\n'
         'element face %d\nproperty list uchar int vertex_indices\nproperty float r\nproperty float g\nproperty float b\n'
         'end_header\n') % (len(p), len(f))
    h += ''.join('%g %g %g %g %g %g %g %g 0.5 0.5 0.5\n' % (p[k] + n[k] + t[k]) for k in range(len(p)))
    h += ''.join('3 %d %d %d 0.5 0.5 0.5\n' % tri for tri in f)
    return h.encode()

def serialized_bytes(shapes=8):
    """Mitsuba 'serialized' v4 (zlib) with `shapes` copies of the sphere and the offset table."""
    p, n, t, f = sphere()
    body = struct.pack('<I', 0x1000 | 0x0001 | 0x0002) + b'standin\0' + struct.pack('<QQ', len(p), len(f))
    body += b''.join(struct.pack('<3f', *v) for v in p) + b''.join(struct.pack('<3f', *v) for v in n)
    body += b''.join(struct.pack('<2f', *v) for v in t) + b''.join(struct.pack('<3I', *v) for v in f)
    one = struct.pack('<HH', 0x041C, 4) + zlib.compress(body)
    return one * shapes + b''.join(struct.pack('<Q', k * len(one)) for k in range(shapes)) + struct.pack('<I', shapes)

def png_bytes(w=8, h=8):
    def chunk(tag, data):
        return struct.pack('>I', len(data)) + tag + data + struct.pack('>I', zlib.crc32(tag + data))
    raw = b''.join(b'\0' + bytes([128] * 3 * w) for _ in range(h))
    return (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0))
            + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))

def bmp_bytes(w=8, h=8):
    row = bytes([128] * 3 * w)
    data = row * h
    return (b'BM' + struct.pack('<IHHI', 54 + len(data), 0, 0, 54)
            + struct.pack('<IiiHHIIiiII', 40, w, h, 1, 24, 0, len(data), 2835, 2835, 0, 0) + data)

def vol_bytes(channels, res=4):
    hdr = b'VOL' + bytes([3]) + struct.pack('<iiiii', 1, res, res, res, channels) + struct.pack('<6f', 0, 0, 0, 1, 1, 1)
    return hdr + struct.pack('<%df' % (res ** 3 * channels), *([0.5] * (res ** 3 * channels)))

# A grey 8x4 RGB float EXR and an 8x8 grey JPEG, written once with Mitsuba 3.9.1's Bitmap.
EXR = base64.b64decode(
    'di8xAQIAAABjaGFubmVscwBjaGxpc3QANwAAAEIAAgAAAAAAAAABAAAAAQAAAEcAAgAAAAAAAAABAAAAAQAAAFIAAgAA'
    'AAAAAAABAAAAAQAAAABjb21wcmVzc2lvbgBjb21wcmVzc2lvbgABAAAABGRhdGFXaW5kb3cAYm94MmkAEAAAAAAAAAAA'
    'AAAABwAAAAMAAABkaXNwbGF5V2luZG93AGJveDJpABAAAAAAAAAAAAAAAAcAAAADAAAAZ2VuZXJhdGVkQnkAc3RyaW5n'
    'ABUAAABNaXRzdWJhIHZlcnNpb24gMy45LjFsaW5lT3JkZXIAbGluZU9yZGVyAAEAAAAAcGl4ZWxBc3BlY3RSYXRpbwBm'
    'bG9hdAAEAAAAAACAP3NjcmVlbldpbmRvd0NlbnRlcgB2MmYACAAAAAAAAAAAAAAAc2NyZWVuV2luZG93V2lkdGgAZmxv'
    'YXQABAAAAAAAgD8AbQEAAAAAAAAAAAAAKQAAAOAH4AcBIAAAAAAAAAACAAAAAwAAAEMAAAAAAAAABCCAn8psfymx/Kag')
JPG = base64.b64decode(
    '/9j/4AAQSkZJRgABAQAAAQABAAD/2wBDAAEBAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEB'
    'AQEBAQEBAQEBAQEBAQEBAQEBAQH/2wBDAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEBAQEB'
    'AQEBAQEBAQEBAQEBAQEBAQEBAQH/wAARCAAEAAgDAREAAhEBAxEB/8QAHwAAAQUBAQEBAQEAAAAAAAAAAAECAwQFBgcI'
    'CQoL/8QAtRAAAgEDAwIEAwUFBAQAAAF9AQIDAAQRBRIhMUEGE1FhByJxFDKBkaEII0KxwRVS0fAkM2JyggkKFhcYGRol'
    'JicoKSo0NTY3ODk6Q0RFRkdISUpTVFVWV1hZWmNkZWZnaGlqc3R1dnd4eXqDhIWGh4iJipKTlJWWl5iZmqKjpKWmp6ip'
    'qrKztLW2t7i5usLDxMXGx8jJytLT1NXW19jZ2uHi4+Tl5ufo6erx8vP09fb3+Pn6/8QAHwEAAwEBAQEBAQEBAQAAAAAA'
    'AAECAwQFBgcICQoL/8QAtREAAgECBAQDBAcFBAQAAQJ3AAECAxEEBSExBhJBUQdhcRMiMoEIFEKRobHBCSMzUvAVYnLR'
    'ChYkNOEl8RcYGRomJygpKjU2Nzg5OkNERUZHSElKU1RVVldYWVpjZGVmZ2hpanN0dXZ3eHl6goOEhYaHiImKkpOUlZaX'
    'mJmaoqOkpaanqKmqsrO0tba3uLm6wsPExcbHyMnK0tPU1dbX2Nna4uPk5ebn6Onq8vP09fb3+Pn6/9oADAMBAAIRAxEA'
    'PwD93P8A6/6bv/iR/TGFwAf/2Q==')

def standin(path):
    ext = os.path.splitext(path)[1].lower()
    name = os.path.basename(path).lower()
    if ext == '.obj': return obj_bytes()
    if ext == '.ply': return ply_bytes()
    if ext == '.serialized': return serialized_bytes()
    if ext == '.exr': return EXR
    if ext == '.png': return png_bytes()
    if ext in ('.jpg', '.jpeg'): return JPG
    if ext == '.bmp': return bmp_bytes()
    if ext == '.vol': return vol_bytes(3 if re.search('albedo|radiance|color|rgb', name) else 1)
    if ext == '.spd': return b'400 1\n700 1\n'
    return None

# ---- top-level scenes ----------------------------------------------------------------------
xmls, included = [], set()
for root, _, files in os.walk(work):
    for fn in files:
        if not fn.endswith('.xml'): continue
        path = os.path.join(root, fn)
        try:
            tree = ET.parse(path)
        except ET.ParseError:
            xmls.append(path); continue
        if tree.getroot().tag != 'scene': continue
        xmls.append(path)
        for inc in tree.getroot().iter('include'):
            f = inc.get('filename', '')
            # Mitsuba resolves an include against the including file's folder, then <path>s.
            for base in (root, os.path.dirname(root)):
                included.add(os.path.normpath(os.path.join(base, f)))
scenes = sorted(p for p in xmls if os.path.normpath(p) not in included)

missing_file = re.compile(r'refers to a missing file "([^"]+)"|spectrum file "([^"]+)" not found')
missing_dir = re.compile(r'<path>: folder "([^"]+)" not found')
unsupported = re.compile(r'unsupported (\w+) plugin "([^"]+)"')
unknown_param = re.compile(r'unknown parameter "([^"]+)" \(\w+\) for plugin "([^"]+)"')
as_texture = re.compile(r'<\w+ type="([^"]+)"[^>]*>: parameter "(\w+)" as a texture is not supported')
unknown_elem = re.compile(r'unknown element <(\w+)>|<(\w+)>: unexpected attribute "(\w+)"')
located = re.compile(r'^mfrender: error: [^:]+:\d+: ')

def inside(p):
    return os.path.realpath(p).startswith(os.path.realpath(work) + os.sep)

rows, reasons = [], collections.Counter()
for scene in scenes:
    rel = os.path.relpath(scene, work)
    stood = 0
    for _ in range(64):
        r = subprocess.run([mfrender, '--check', rel] + extra, cwd=work, capture_output=True, text=True)
        created = False
        for line in r.stderr.splitlines():
            m = missing_dir.search(line)
            if m and inside(os.path.join(work, m.group(1))):
                os.makedirs(os.path.join(work, m.group(1)), exist_ok=True); created = True
            m = missing_file.search(line)
            if m:
                target = os.path.join(work, m.group(1) or m.group(2))
                data = standin(target)
                if data is not None and inside(target) and not os.path.exists(target):
                    os.makedirs(os.path.dirname(target), exist_ok=True)
                    with open(target, 'wb') as out: out.write(data)
                    stood += 1; created = True
        if not created: break
    if r.returncode == 0:
        rows.append((rel, 'opens', stood, '')); continue
    why = []
    for line in r.stderr.splitlines():
        m = unsupported.search(line)
        if m: why.append('%s:%s' % (m.group(1), m.group(2))); continue
        m = unknown_param.search(line)
        if m: why.append('%s.%s' % (m.group(2), m.group(1))); continue
        m = as_texture.search(line)
        if m: why.append('%s.%s (texture)' % (m.group(1), m.group(2))); continue
        m = unknown_elem.search(line)
        if m: why.append('<%s>' % m.group(1) if m.group(1) else '<%s %s=...>' % (m.group(2), m.group(3))); continue
        m = missing_file.search(line)  # a data file no stand-in exists for (its format is not read)
        if m: why.append('no stand-in for *%s' % os.path.splitext(m.group(1) or m.group(2))[1])
    if why:
        why = sorted(set(why))
        reasons.update(why)
        rows.append((rel, 'refused', stood, ', '.join(why)))
    else:
        first = next((l for l in r.stderr.splitlines() if l.startswith('mfrender: error')), r.stderr.strip()[:200])
        rows.append((rel, 'other', stood, located.sub('', first)))

print('scene\tclass\tstand-ins\treasons')
for row in rows: print('%s\t%s\t%d\t%s' % row)
n = collections.Counter(r[1] for r in rows)
print('\n# %d scenes: %d open, %d refused, %d other' % (len(rows), n['opens'], n['refused'], n['other']))
print('# scenes refused per reason:')
for why, k in reasons.most_common(): print('%d\t%s' % (k, why))
PY
