#!/usr/bin/env python3
"""The example scenes of scenes/mitsuba/ in Mitsuba 3 (scalar_rgb, with the macrofacet plugin)
and in mfrender, from the same files:

1. the committed boundary of the fuzzy torus is what `python3 -m macrofacet_mitsuba enclosure`
   writes (byte for byte);
2. each scene (and a test scene with anisotropic roughness on a rotated sphere), K seeds per renderer: image means within 2 % per channel and within 4.5 combined
   standard errors + 1 %, 8x8 blocks as cpp_host/tests/mitsuba/compare.py judges them, and the
   per-pixel differences at noise level: R = sum (mean_a - mean_b)^2 / sum (var_a + var_b) / K
   over all pixel values is 1 in expectation when both renderers converge to the same image;
   it must stay below 1.3;
3. the thin shell (sigma = 1e-4 of the radius, single scattering) against Mitsuba's own
   roughconductor, which uses the separable Smith G1(wi) G1(wo) where a thin shell produces the
   height-correlated 1 / (1 + Lambda_i + Lambda_o) (cpp_host/tests/test_macrofacet.cpp,
   thin_shell): the difference is accounted for pixel by pixel with mfrender's roughconductor
   rendered both ways with one seed (identical samples, only the G weights differ). Over the
   pixels that see the sphere at cos >= 0.35: mean within 1.5 % and 4.5 SE + 0.5 %, R < 1.3;
4. spatially varying media (issue 12), the same files in both renderers (field_data.py writes
   their grids and textures): data/varying_media.xml (sigma and roughness gridvolumes, the
   roughness's wrap_mode repeat, a bitmap over the sphere's uv; a 6-channel anisotropy grid)
   and data/sdf_sphere.xml (an sdfgrid mean surface), judged as in 2; the plugin's reports name
   the wrap mode it read from the grid; a constvolume parameter renders in the plugin exactly
   as the number (same seed, identical images); a piecewise-constant field (sigma and alpha per
   half) renders each half as the stationary medium (piecewise_constant_field); the sdfgrid
   sphere renders as the analytic sphere in the plugin;
5. the library's GTR distribution (issue 13: distribution gtr, gamma, lambda exact or dimov)
   passes through the plugin by name: a GTR thin shell, judged as in 2;
6. the plugin's counters: no majorant violation, no unprepared call, no library error.

--only GROUP runs one group (scenes: 1-2, roughconductor: 3, varying: 4, gtr: 5) while developing.

Exit status 77 (skipped) without Mitsuba. usage: test_renders.py --mfrender PATH --work DIR [--runs K]"""
import argparse
import math
import os
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SCENES = os.path.join(ROOT, "scenes", "mitsuba")
sys.path.insert(0, os.path.join(ROOT, "cpp_host", "tests", "mitsuba"))

import field_data  # noqa: E402
from plugin_env import SKIPPED, Checks, mitsuba_with_plugin  # noqa: E402

# (scene, -D overrides): small images, enough samples for the statistics. aniso_shell (a test
# scene) checks the tangent: a wrong pole of the sphere's dp/du gives R ~ 90 there.
SCENE_RUNS = [
    (os.path.join(SCENES, "thin_shell_sphere.xml"), {"res": "48", "spp": "32"}),
    (os.path.join(SCENES, "fuzzy_torus.xml"), {"res": "40", "spp": "16", "max_depth": "8"}),
    (os.path.join(HERE, "data", "aniso_shell.xml"), {"res": "48", "spp": "64"}),
]
THIN = {"res": "40", "spp": "64", "max_depth": "2", "sigma": "0.0001", "boundary_radius": "1.0003"}


def mean_var(runs):
    """Per pixel value: mean and variance over the runs (lists of equal length)."""
    K = len(runs)
    n = len(runs[0])
    mean = [sum(r[i] for r in runs) / K for i in range(n)]
    var = [sum((r[i] - mean[i]) ** 2 for r in runs) / (K - 1) for i in range(n)]
    return mean, var


def noise_ratio(a_runs, b_runs, idx=None):
    """R of the module docstring over the value indices idx (all when None)."""
    ma, va = mean_var(a_runs)
    mb, vb = mean_var(b_runs)
    idx = range(len(ma)) if idx is None else idx
    num = sum((ma[i] - mb[i]) ** 2 for i in idx)
    den = sum((va[i] / len(a_runs) + vb[i] / len(b_runs)) for i in idx)
    return num / den if den > 0 else float("inf")


class Renderers:
    def __init__(self, mi, mfrender, work):
        self.mi, self.mfrender, self.work = mi, mfrender, work
        self.media = []

    def mitsuba(self, scene, overrides, seed, name):
        mi = self.mi
        sc = mi.load_file(scene, **overrides)
        img = mi.render(sc, seed=seed)
        for shape in sc.shapes():
            m = shape.interior_medium()
            if m is not None and "MacrofacetMedium" in str(m):
                self.media.append(str(m))
        mi.util.write_bitmap(os.path.join(self.work, f"{name}_mi{seed}.exr"), img, write_async=False)
        return list(img.array), img.shape[1], img.shape[0]

    def mf(self, scene, overrides, seed, name):
        import compare
        out = os.path.join(self.work, f"{name}_mf{seed}.exr")
        defs = [x for k, v in overrides.items() for x in ("-D", f"{k}={v}")]
        subprocess.run([self.mfrender, scene, "-o", out, "--quiet", "--seed", str(seed)] + defs, check=True)
        w, h, flat = compare.read(self.mi, out)
        return flat, w, h


def compare_scene(check, r, scene, overrides, K):
    import compare
    name = os.path.splitext(os.path.basename(scene))[0]
    t0 = time.time()
    mi_runs = [r.mitsuba(scene, overrides, 2000 + k, name) for k in range(K)]
    t1 = time.time()
    mf_runs = [r.mf(scene, overrides, 1000 + k, name) for k in range(K)]
    t2 = time.time()
    w, h = mi_runs[0][1], mi_runs[0][2]
    ok, report = compare.judge([(w, h, x[0]) for x in mf_runs], [(w, h, x[0]) for x in mi_runs], 0.01)
    check(ok, f"{name}: mfrender vs Mitsuba+plugin: {report}")
    n = len(mi_runs[0][0]) // 3
    worst = 0.0
    for c in range(3):
        a = sum(sum(x[0][c::3]) / n for x in mf_runs) / K
        b = sum(sum(x[0][c::3]) / n for x in mi_runs) / K
        worst = max(worst, abs(a - b) / b)
    check(worst < 0.02, f"{name}: largest channel-mean difference {100 * worst:.2f} % (< 2 %)")
    R = noise_ratio([x[0] for x in mf_runs], [x[0] for x in mi_runs])
    check(R < 1.3, f"{name}: per-pixel differences / noise R = {R:.3f} (< 1.3; 1 = noise only)")
    print(f"  {name}: {w}x{h}, {overrides.get('spp')} spp, {K} seeds: Mitsuba+plugin {(t1 - t0) / K:.2f} s, "
          f"mfrender {(t2 - t1) / K:.2f} s per image", flush=True)


def roughconductor_scene(src, dst, separable_only):
    """The scene with the macrofacet sphere replaced by the same sphere as a roughconductor with
    the medium's distribution, alpha and material (and, for mfrender, its shadowing)."""
    tree = ET.parse(src)
    root = tree.getroot()
    med = root.find("medium[@type='macrofacet']")
    params = {e.get("name"): e.get("value") for e in med if e.tag in ("string", "float")}
    radius = med.find("shape[@name='mean_surface']/float[@name='radius']")
    root.remove(med)
    boundary = next(s for s in root.findall("shape") if s.find(f"ref[@id='{med.get('id')}']") is not None)
    for child in list(boundary):
        boundary.remove(child)
    ET.SubElement(boundary, "float", name="radius", value=radius.get("value") if radius is not None else "1")
    bsdf = ET.SubElement(boundary, "bsdf", type="roughconductor")
    for key in ("distribution", "material"):
        ET.SubElement(bsdf, "string", name=key, value=params[key])
    ET.SubElement(bsdf, "float", name="alpha", value=params["alpha"])
    paths = {}
    for mode in (["separable"] if separable_only else ["separable", "height_correlated"]):
        if not separable_only:
            for e in bsdf.findall("string[@name='shadowing']"):
                bsdf.remove(e)
            ET.SubElement(bsdf, "string", name="shadowing", value=mode)
        paths[mode] = dst.replace(".xml", f"_{mode}.xml")
        tree.write(paths[mode])
    return paths


def thin_mask(w, h, fov_deg=40.0, cos_min=0.35):
    """Pixel indices whose centre ray (camera at (0, 0, 4) looking at the origin) meets the unit
    sphere at cos(view, normal) >= cos_min (the mask of test_macrofacet.cpp's thin_shell)."""
    th = math.tan(math.radians(fov_deg) / 2)
    out = []
    for y in range(h):
        for x in range(w):
            dx, dy, dz = (1 - 2 * (x + 0.5) / w) * th, (1 - 2 * (y + 0.5) / h) * th * h / w, -1.0
            n = math.sqrt(dx * dx + dy * dy + dz * dz)
            dx, dy, dz = dx / n, dy / n, dz / n
            b = 4 * dz
            disc = b * b - 15
            if disc <= 0:
                continue
            t = -b - math.sqrt(disc)
            px, py, pz = dx * t, dy * t, 4 + dz * t
            if -(px * dx + py * dy + pz * dz) >= cos_min:
                out.append(y * w + x)
    return out


def thin_shell_vs_roughconductor(check, r, K):
    scene = os.path.join(SCENES, "thin_shell_sphere.xml")
    rc_mi = roughconductor_scene(scene, os.path.join(r.work, "thin_rc.xml"), True)["separable"]
    rc_mf = roughconductor_scene(scene, os.path.join(r.work, "thin_rc_mf.xml"), False)
    shell = [r.mitsuba(scene, THIN, 3000 + k, "thin_shell")[0] for k in range(K)]
    surface = {k: v for k, v in THIN.items() if k not in ("sigma", "boundary_radius")}  # the medium's only
    rough = [r.mitsuba(rc_mi, surface, 4000 + k, "thin_rc")[0] for k in range(K)]
    # mfrender: separable and height-correlated with one seed and 4x the samples
    many = dict(surface, spp=str(4 * int(THIN["spp"])))
    sep = r.mf(rc_mf["separable"], many, 7, "thin_sep")[0]
    hc = r.mf(rc_mf["height_correlated"], many, 7, "thin_hc")[0]
    w = h = int(THIN["res"])
    idx = [3 * p + c for p in thin_mask(w, h) for c in range(3)]
    # the expected thin shell: Mitsuba's separable image times height-correlated / separable
    expected = [[x[i] * (hc[i] / sep[i] if sep[i] > 0 else 1.0) for i in range(len(x))] for x in rough]
    a = [sum(x[i] for i in idx) for x in shell]
    b = [sum(x[i] for i in idx) for x in expected]
    ma, mb = sum(a) / K, sum(b) / K
    se = math.sqrt(sum((v - ma) ** 2 for v in a) / (K - 1) / K + sum((v - mb) ** 2 for v in b) / (K - 1) / K)
    deficit = 1 - sum(sep[i] for i in idx) / sum(hc[i] for i in idx)
    rel = (ma - mb) / mb
    check(abs(rel) < 0.015 and abs(ma - mb) < 4.5 * se + 0.005 * mb,
          f"thin shell vs roughconductor (x height-correlated/separable, deficit {100 * deficit:.3f} %): "
          f"{len(idx) // 3} pixels, mean {100 * rel:+.2f} % = {(ma - mb) / se:+.2f} se")
    R = noise_ratio(shell, expected, idx)
    check(R < 1.3, f"thin shell vs roughconductor: per-pixel differences / noise R = {R:.3f} (< 1.3)")


# A sphere whose roughness and tint are numbers or the same values as constvolumes: the plugin
# must render both identically (0.3 is not a float: the constvolume keeps 0.3f, the plugin reads
# it back as the number written). The box filter keeps every sample in its block: with Mitsuba's
# default gaussian, blocks overlap at their borders and are summed in thread order, which
# changes pixel values there by an ulp from one render to the next.
CONSTANT_SCENE = """<scene version="3.0.0"><integrator type="volpath"><integer name="max_depth" value="4"/></integrator>
    <sensor type="perspective"><transform name="to_world"><lookat origin="0, 1, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="8"/></sampler>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/><rfilter type="box"/></film></sensor>
    <emitter type="point"><point name="position" x="2" y="3" z="4"/><rgb name="intensity" value="20"/></emitter>
    <medium type="macrofacet" id="m"><float name="sigma" value="0.01"/>{params}<shape type="sphere" name="mean_surface"/></medium>
    <shape type="sphere"><float name="radius" value="1.03"/><bsdf type="null"/><ref name="interior" id="m"/></shape></scene>"""
NUMBERS = '<float name="alpha" value="0.3"/><rgb name="specular_reflectance" value="0.9, 0.7, 0.55"/>'
CONSTVOLUMES = ('<volume name="alpha" type="constvolume"><float name="value" value="0.3"/></volume>'
                '<volume name="specular_reflectance" type="constvolume"><rgb name="value" value="0.9, 0.7, 0.55"/></volume>')


def varying_media(check, r, K):
    mi = r.mi
    first = len(r.media)
    compare_scene(check, r, field_data.write_varying_media(mi, r.work), {"res": "48", "spp": "32"}, K)
    reports = r.media[first:]
    check(any("field alpha = <volume type=\"gridvolume\"> (2 x 4 x 2, wrap_mode repeat)" in m for m in reports)
          and any("field sigma = <volume type=\"gridvolume\"> (8 x 2 x 2, wrap_mode clamp)" in m for m in reports),
          "the plugin read the grids' wrap modes from Mitsuba's values: " + next((m[m.find("field"):] for m in reports if "field alpha" in m), "?"))
    compare_scene(check, r, field_data.write_sdf_sphere(mi, r.work), {"res": "32", "spp": "16"}, K)
    images = [list(mi.render(mi.load_string(CONSTANT_SCENE.format(params=p)), seed=5).array) for p in (NUMBERS, CONSTVOLUMES)]
    same = sum(a == b for a, b in zip(*images))
    check(same == len(images[0]) and sum(images[0]) > 0,
          f"constvolumes render as the numbers: {same} of {len(images[0])} pixel values identical (same seed)")


# A sphere seen along -z whose halves x < 0 and x > 0 have different sigma and roughness: numbers
# (a stationary medium) or one gridvolume per parameter, 2 x 1 x 1 cells, filter_type nearest (a
# piecewise-constant field). The boundary sphere contains the region at the larger sigma.
HALVES_SCENE = """<scene version="3.0.0"><integrator type="volpath"><integer name="max_depth" value="4"/></integrator>
    <sensor type="perspective"><float name="fov" value="36"/><transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
        <film type="hdrfilm"><integer name="width" value="40"/><integer name="height" value="32"/><rfilter type="box"/></film></sensor>
    <shape type="sphere"><point name="center" x="0" y="3" z="4"/><float name="radius" value="1.5"/><emitter type="area"><rgb name="radiance" value="3"/></emitter></shape>
    <emitter type="constant"><rgb name="radiance" value="0.1"/></emitter>
    <medium type="macrofacet" id="m">{params}<string name="material" value="Cu"/><shape type="sphere" name="mean_surface"/></medium>
    <shape type="sphere"><float name="radius" value="1.07"/><bsdf type="null"/><ref name="interior" id="m"/></shape></scene>"""
HALF_VALUES = {"sigma": (0.005, 0.02), "alpha": (0.1, 0.4)}


def halves_params(side):
    """The medium's numbers of one half (side 0: x < 0, 1: x > 0), or None: both as grids."""
    if side is not None:
        return "".join(f'<float name="{k}" value="{v[side]}"/>' for k, v in HALF_VALUES.items())
    return "".join(f'<volume name="{k}" type="gridvolume"><string name="filename" value="halves_{k}.vol"/>'
                   '<string name="filter_type" value="nearest"/>'
                   '<transform name="to_world"><scale value="2.4"/><translate x="-1.2" y="-1.2" z="-1.2"/></transform></volume>'
                   for k in HALF_VALUES)


def render_runs(mi, xml, K, seed0, cwd=None):
    """K renders of the scene `xml` (seeds seed0 ...): their values and the seconds per render."""
    sc = mi.load_string(xml) if cwd is None else mi.load_file(xml)
    t0 = time.time()
    runs = [list(mi.render(sc, seed=seed0 + k).array) for k in range(K)]
    return runs, (time.time() - t0) / K


def piecewise_constant_field(check, r, K):
    """The piecewise-constant field renders each half as the stationary medium of that half. Both
    render with the same seeds (common random numbers: many pixels come out identical, the rest
    differ once the field's majorants, which bound both halves, change the tracker's steps), over
    the pixel columns 4 or more away from the image's middle (paths that cross x = 0 are rare
    there): the paired region-mean difference within 4.5 SE + 1 %, and per-pixel paired
    differences at noise level, R = sum_i mean(d_i)^2 / sum_i var(d_i) / K < 1.5."""
    mi = r.mi
    # At least 8 runs: with 4, each pixel's variance has 3 degrees of freedom and R ranged from
    # 0.61 to 1.50 over seeds 300, 1300 and 2300 of the same renderer.
    K = max(K, 8)
    for k, (lo, hi) in HALF_VALUES.items():
        field_data.write_volume(mi, os.path.join(r.work, f"halves_{k}.vol"), [lo, hi], (2, 1, 1))
    cwd = os.getcwd()
    os.chdir(r.work)  # the grids' filenames are relative
    try:
        field, t_field = render_runs(mi, HALVES_SCENE.format(params=halves_params(None)), K, 300)
        halves = [render_runs(mi, HALVES_SCENE.format(params=halves_params(side)), K, 300) for side in (0, 1)]
    finally:
        os.chdir(cwd)
    w, h = 40, 32
    for side, (stationary, _) in enumerate(halves):
        columns = range(0, w // 2 - 4) if side == 0 else range(w // 2 + 4, w)
        idx = [3 * (y * w + x) + c for y in range(h) for x in columns for c in range(3)]
        same = sum(f[i] == s[i] for f, s in zip(field, stationary) for i in idx)
        d = [[f[i] - s[i] for i in idx] for f, s in zip(field, stationary)]
        dm, dv = mean_var(d)
        den = sum(dv) / K
        R = sum(x * x for x in dm) / den if den > 0 else 0.0
        diff = [sum(run) / len(idx) for run in d]
        mean_d = sum(diff) / K
        se = math.sqrt(sum((x - mean_d) ** 2 for x in diff) / (K - 1) / K)
        b = sum(sum(s[i] for i in idx) / len(idx) for s in stationary) / K
        z = mean_d / se if se > 0 else 0.0
        half = "x < 0" if side == 0 else "x > 0"
        check(abs(mean_d) <= 4.5 * se + 0.01 * b and R < 1.5,
              f"piecewise-constant field, half {half} ({', '.join(f'{k} {v[side]}' for k, v in HALF_VALUES.items())}) vs the stationary "
              f"medium, same seeds: mean difference {mean_d:+.2e} of {b:.5f} (z = {z:+.2f}), per-pixel paired R = {R:.3f} (< 1.5), "
              f"{same} of {K * len(idx)} values identical")
    print(f"  piecewise field: {t_field:.3f} s per render; stationary halves {halves[0][1]:.3f} s, {halves[1][1]:.3f} s "
          f"(ratio {t_field / max(halves[0][1], halves[1][1]):.2f} to the slower)", flush=True)


def sdf_sphere_vs_analytic(check, r, K):
    """data/sdf_sphere.xml's sdfgrid (41^3 nodes of the unit sphere's distance) renders as the
    analytic unit sphere in the plugin: judged as compare_scene's renders."""
    import compare
    mi = r.mi
    grid = field_data.write_sdf_sphere(mi, r.work)
    tree = ET.parse(grid)
    med = tree.getroot().find("medium[@type='macrofacet']")
    med.remove(med.find("shape[@name='mean_surface']"))
    ET.SubElement(med, "shape", {"type": "sphere", "name": "mean_surface"})
    analytic = os.path.join(r.work, "sdf_sphere_analytic.xml")
    tree.write(analytic)
    runs = {}
    for name, scene in (("sdfgrid", grid), ("sphere", analytic)):
        sc = mi.load_file(scene, res="32", spp="16")
        t0 = time.time()
        runs[name] = ([list(mi.render(sc, seed=500 + 10 * len(runs) + k).array) for k in range(K)], (time.time() - t0) / K)
    w = h = 32
    ok, report = compare.judge([(w, h, x) for x in runs["sdfgrid"][0]], [(w, h, x) for x in runs["sphere"][0]], 0.01)
    R = noise_ratio(runs["sdfgrid"][0], runs["sphere"][0])
    check(ok and R < 1.3, f"sdfgrid sphere vs analytic sphere (plugin): {report}; per-pixel R = {R:.3f} (< 1.3)")
    print(f"  sdfgrid {runs['sdfgrid'][1]:.3f} s, analytic sphere {runs['sphere'][1]:.3f} s per render", flush=True)


def gtr_medium(check, r, K):
    """The library's GTR distribution (issue 13: distribution gtr, gamma, lambda) passes through the
    plugin by name: a thin GTR shell renders in the plugin as in mfrender from one file, with both
    of the library's Lambda functions."""
    mi = r.mi
    src = os.path.join(SCENES, "thin_shell_sphere.xml")
    for lam in ("exact", "dimov"):
        tree = ET.parse(src)
        med = tree.getroot().find("medium[@type='macrofacet']")
        for e in list(med):
            if e.get("name") == "distribution":
                med.remove(e)
        for tag, name, value in (("string", "distribution", "gtr"), ("float", "gamma", "1.5"), ("string", "lambda", lam)):
            med.insert(0, ET.Element(tag, {"name": name, "value": value}))
        path = os.path.join(r.work, f"gtr_shell_{lam}.xml")
        tree.write(path)
        compare_scene(check, r, path, {"res": "32", "spp": "32"}, K)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mfrender", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--runs", type=int, default=4)
    ap.add_argument("--only", choices=("scenes", "roughconductor", "varying", "gtr"), help="run one group of checks (while developing)")
    a = ap.parse_args()
    mi = mitsuba_with_plugin()
    if mi is None:
        return SKIPPED
    import macrofacet_mitsuba
    os.makedirs(a.work, exist_ok=True)
    check = Checks()

    run = lambda group: a.only in (None, group)  # noqa: E731
    fresh = os.path.join(a.work, "fuzzy_torus_boundary.ply")
    macrofacet_mitsuba.write_enclosure(os.path.join(ROOT, "scenes", "torus.obj"), fresh, sigma=0.08, scale=2)
    with open(fresh, "rb") as f1, open(os.path.join(SCENES, "fuzzy_torus_boundary.ply"), "rb") as f2:
        check(f1.read() == f2.read(), "scenes/mitsuba/fuzzy_torus_boundary.ply is the enclosure tool's output "
                                      "(regenerate it with the command in fuzzy_torus.xml)")

    r = Renderers(mi, a.mfrender, a.work)
    if run("scenes"):
        for scene, overrides in SCENE_RUNS:
            compare_scene(check, r, scene, overrides, a.runs)
    if run("roughconductor"):
        thin_shell_vs_roughconductor(check, r, a.runs)
    if run("varying"):
        varying_media(check, r, a.runs)
        piecewise_constant_field(check, r, a.runs)
        sdf_sphere_vs_analytic(check, r, a.runs)
    if run("gtr"):
        gtr_medium(check, r, a.runs)

    bad = [m for m in r.media if not all(f"{k} = 0" in m for k in ("majorant_violations", "unprepared_calls", "errors"))]
    check(not bad, f"plugin counters over {len(r.media)} renders: no majorant violation, unprepared call or error"
                   + (f" ({bad[0]})" if bad else ""))
    return check.exit_status()


if __name__ == "__main__":
    sys.exit(main())
