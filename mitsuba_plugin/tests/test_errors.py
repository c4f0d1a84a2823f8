#!/usr/bin/env python3
"""The Mitsuba plugin's errors: every bad input raises a Mitsuba error (RuntimeError) that names the
parameter or element at fault, the Python process survives them all and renders afterwards;
calls outside volpath's sequence (from Python) return an empty medium instead of crashing; the
enclosure tool reports bad input with exit status 1.

Needs the plugin's package on PYTHONPATH (ctest sets it); exit status 77 (skipped) without
Mitsuba. usage: test_errors.py"""
import math
import os
import subprocess
import sys
import tempfile

from plugin_env import SKIPPED, Checks, mitsuba_with_plugin

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
TORUS = os.path.join(ROOT, "scenes", "torus.obj")

SIGMA = '<float name="sigma" value="0.01"/>'
ALPHA = '<float name="alpha" value="0.3"/>'
SPHERE = '<shape type="sphere" name="mean_surface"/>'


def medium(body, mean=SPHERE):
    return f'<medium version="3.0.0" type="macrofacet" id="m">{body}{mean}</medium>'


# (what, XML, fragments the message must contain)
CASES = [
    ("unknown parameter", medium(SIGMA + ALPHA + '<float name="ndf" value="1"/>'), ['unknown parameter "ndf"']),
    ("negative sigma", medium('<float name="sigma" value="-1"/>' + ALPHA), ['parameter "sigma"', "> 0"]),
    ("missing sigma", medium(ALPHA), ['"sigma"']),
    ("sigma and variance", medium(SIGMA + ALPHA + '<float name="variance" value="0.01"/>'), ['"variance"']),
    ("unknown material", medium(SIGMA + ALPHA + '<string name="material" value="Unobtainium"/>'), ['parameter "material"', "Unobtainium"]),
    ("bad distribution", medium(SIGMA + ALPHA + '<string name="distribution" value="phong"/>'), ['distribution', "phong"]),
    ("negative alpha", medium(SIGMA + '<float name="alpha" value="-0.3"/>'), ['"alpha"']),
    ("reflectance > 1", medium(SIGMA + ALPHA + '<string name="micro_bsdf" value="diffuse"/><rgb name="reflectance" value="1.5"/>'),
     ['"reflectance"']),
    ("boolean", medium(SIGMA + '<boolean name="alpha" value="true"/>'), ['parameter "alpha" is a boolean']),
    ("vector", medium(SIGMA + '<vector name="alpha" x="1" y="2" z="3"/>'), ['parameter "alpha" has type vector']),
    ("spectrum list", medium(SIGMA + ALPHA + '<spectrum name="eta" value="400:1, 500:2"/>'), ['parameter "eta"', "wavelength"]),
    ("no mean surface", medium(SIGMA + ALPHA, ""), ['mean_surface']),
    ("mean surface misnamed", medium(SIGMA + ALPHA, '<shape type="sphere" name="surface"/>'), ['"surface"', "mean_surface"]),
    ("mean surface a disk", medium(SIGMA + ALPHA, '<shape type="disk" name="mean_surface"/>'), ["mean_surface", "a sphere, a closed triangle mesh"]),
    ("mean surface a rectangle", medium(SIGMA + ALPHA, '<shape type="rectangle" name="mean_surface"/>'), ["mean_surface", "closed triangle mesh"]),
    ("mean surface flipped mesh", medium(SIGMA + ALPHA, f'<shape type="obj" name="mean_surface"><string name="filename" value="{TORUS}"/>'
                                                        '<boolean name="flip_normals" value="true"/></shape>'), ["mean_surface", "flip_normals"]),
    ("nested phase", medium(SIGMA + ALPHA + '<phase type="hg"/>'), ["<phase>"]),
    ("Mitsuba's sample_emitters", medium(SIGMA + ALPHA + '<boolean name="sample_emitters" value="false"/>'), ['"sample_emitters"']),
]


def grid(name, filename, to_world="", extra=""):
    """A gridvolume for parameter `name` over `filename`."""
    return (f'<volume name="{name}" type="gridvolume"><string name="filename" value="{filename}"/>{extra}'
            f'<transform name="to_world">{to_world}</transform></volume>')


# a box that covers the unit sphere's medium at sigma <= 0.03 (region [-1.1, 1.1]^3)
COVERING = '<scale value="3"/><translate x="-1.5" y="-1.5" z="-1.5"/>'


def varying_cases(mi, tmp):
    """Bad spatially varying parameters (issue 12): each refused at load, naming the parameter and
    what is wrong with it."""
    import field_data

    def vol(name, values, n=(2, 2, 2), channels=1):
        path = os.path.join(tmp, name)
        field_data.write_volume(mi, path, values, n, channels)
        return path

    ok = vol("alpha_ok.vol", [0.2, 0.3] * 4)
    negative = vol("alpha_negative.vol", [0.2, 0.3, 0.2, -0.1, 0.2, 0.3, 0.2, 0.3])
    nan = vol("sigma_nan.vol", [0.01] * 5 + [float("nan")] + [0.01] * 2)
    not_pd = vol("aniso_not_pd.vol", [1e-3, 1e-3, 1e-3, 2e-3, 0, 0] * 8, channels=6)
    texture_no_uv = os.path.join(tmp, "tint.exr")
    mi.Bitmap(mi.TensorXf([0.5] * 12, (2, 2, 3))).write(texture_no_uv)
    sdf = vol("sphere_sdf.vol", field_data.sphere_sdf(9, 1.5), (9, 9, 9))
    sdf_mean = (f'<shape type="sdfgrid" name="mean_surface"><string name="filename" value="{sdf}"/>'
                '<transform name="to_world"><scale value="3"/><translate x="-1.5" y="-1.5" z="-1.5"/></transform></shape>')
    return [
        ("grid not covering the medium", medium(SIGMA + grid("alpha", ok)),
         ['parameter "alpha"', "does not cover the medium's region", "wrap_mode repeat"]),
        ("negative voxel", medium(SIGMA + grid("alpha", negative, COVERING)), ['parameter "alpha"', "voxel (1, 1, 0)", "-0.1", "> 0"]),
        ("NaN voxel", medium(ALPHA + grid("sigma", nan, COVERING)), ['parameter "sigma"', "voxel (1, 0, 1)", "nan"]),
        ("anisotropy not positive definite", medium(SIGMA + grid("anisotropy", not_pd, COVERING)),
         ['"anisotropy"', "not positive definite", "voxel (0, 0, 0)"]),
        ("anisotropy as a texture", medium(SIGMA + f'<texture name="anisotropy" type="bitmap"><string name="filename" value="{texture_no_uv}"/></texture>'),
         ['"anisotropy"', "not a texture"]),
        ("texture without uv", medium(SIGMA + f'<texture name="alpha" type="bitmap"><string name="filename" value="{texture_no_uv}"/></texture>', sdf_mean),
         ['parameter "alpha"', "no texture coordinates", "sdfgrid"]),
        ("parameter that cannot vary", medium(SIGMA + ALPHA + grid("eta", ok, COVERING)), ['"eta"', "cannot vary in space"]),
        ("alpha as a 6-channel grid", medium(SIGMA + grid("alpha", not_pd, COVERING)), ['parameter "alpha"', "6 channels", "1 channel"]),
        ("sdfgrid smaller than the medium", medium('<float name="sigma" value="0.2"/>' + ALPHA, sdf_mean),
         ["sdfgrid", "reaches the grid's boundary", "enlarge it"]),
    ]


def main():
    mi = mitsuba_with_plugin()
    if mi is None:
        return SKIPPED
    check = Checks()

    def expect_error(what, fn, fragments):
        try:
            fn()
        except RuntimeError as e:
            msg = str(e)
            check(all(f in msg for f in fragments) and "macrofacet" in msg, f"{what}: {msg.splitlines()[-1][-220:]}")
            return
        check(False, f"{what}: no error")

    # an open mesh: the library refuses it (the interior would be undefined)
    with tempfile.TemporaryDirectory() as tmp:
        tri = os.path.join(tmp, "triangle.obj")
        with open(tri, "w") as f:
            f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
        cases = CASES + [("open mesh", medium(SIGMA + ALPHA, f'<shape type="obj" name="mean_surface"><string name="filename" value="{tri}"/></shape>'),
                          ["mean_surface", "not closed"])]
        cases += varying_cases(mi, tmp)
        for what, xml, fragments in cases:
            expect_error(what, lambda xml=xml: mi.load_string(xml), fragments)

    # the error carries the scene file's position, as Mitsuba's own errors do
    scene = ('<scene version="3.0.0"><medium type="macrofacet" id="gold">\n' + SIGMA + ALPHA +
             '\n<float name="shell_extent" value="-3"/>' + SPHERE + '</medium></scene>')
    expect_error("in a scene", lambda: mi.load_string(scene), ['parameter "shell_extent"', "line 1"])

    # other variants: a clear refusal
    for variant in ("scalar_spectral", "scalar_spectral_polarized"):
        mi.set_variant(variant)
        expect_error(variant, lambda: mi.load_string(medium(SIGMA + ALPHA)), ["scalar_rgb only", "RGB"])
    mi.set_variant("scalar_rgb")

    # calls from Python outside volpath's sequence: an empty medium, counted, no crash
    m = mi.load_string(medium(SIGMA + ALPHA + '<string name="material" value="Au"/>'))
    mei = mi.MediumInteraction3f()
    mei.p, mei.wi, mei.t = mi.Point3f(0, 0, 1.0), mi.Vector3f(0, 0, 1), 1.0
    maj = m.get_majorant(mei)
    coeff = m.get_scattering_coefficients(mei)
    ok = maj[0] == 0 and coeff[2][0] == 0 and "unprepared_calls = 2" in str(m)
    check(ok, f'unprepared calls: majorant {maj}, coefficients {coeff}; {str(m)[-120:]}')
    # the phase function from Python, without a sampler: finite values, pdf > 0 at normal incidence
    ph = m.phase_function()
    ctx = mi.PhaseFunctionContext()
    value, pdf = ph.eval_pdf(ctx, mei, mi.Vector3f(0, 0, 1))
    wo, weight, spdf = ph.sample(ctx, mei, 0.3, mi.Point2f(0.4, 0.6))
    ok = pdf > 0 and all(math.isfinite(v) and v > 0 for v in value) and spdf > 0 and abs(wo[0] ** 2 + wo[1] ** 2 + wo[2] ** 2 - 1) < 1e-5
    check(ok, f'phase function from Python: eval {value} pdf {pdf:.4f}; sample {wo} weight {weight} pdf {spdf:.4f}')

    # after all of that the process still renders: a small valid scene
    sc = mi.load_string(f'''<scene version="3.0.0"><integrator type="volpath"/>
        <sensor type="perspective"><transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler></sensor>
        <emitter type="constant"/>{medium(SIGMA + ALPHA).replace(' version="3.0.0"', '')}
        <shape type="sphere"><float name="radius" value="1.03"/><bsdf type="null"/><ref name="interior" id="m"/></shape></scene>''')
    img = list(mi.render(sc).array)
    ok = all(math.isfinite(v) for v in img) and sum(img) > 0
    check(ok, f'renders after the errors: mean {sum(img) / len(img):.4f}')

    # the enclosure tool: bad input is an error message and exit status 1
    for what, args, fragment in [
        ("enclosure: missing mesh", ["enclosure", "/nonexistent.obj", "/tmp/x.ply", "--sigma", "0.1"], "nonexistent"),
        ("enclosure: negative sigma", ["enclosure", TORUS, "/tmp/x.ply", "--sigma", "-0.1"], "positive"),
        ("enclosure: open mesh", ["enclosure", os.path.join(HERE, "data", "open_square.obj"), "/tmp/x.ply", "--sigma", "0.1"], "not closed"),
    ]:
        r = subprocess.run([sys.executable, "-m", "macrofacet_mitsuba"] + args, capture_output=True, text=True)
        ok = r.returncode == 1 and fragment in r.stderr and "Traceback" not in r.stderr
        check(ok, f'{what}: exit {r.returncode}: {r.stderr.strip()[-160:]}')

    return check.exit_status()


if __name__ == "__main__":
    sys.exit(main())
