//! The C ABI gives the same numbers as the safe core, bit for bit.
//!
//! Every `extern "C"` query of `macrofacet_ffi` is called (as a C host would, through raw
//! pointers) for many seeded random inputs on media covering the parameter table, and compared
//! with `medium_from_params` + the core methods on the same inputs, preprocessed exactly as the
//! documented contract says (frame from normal and tangent, world directions checked to unit
//! length and taken to the local frame). No tolerance: the FFI layer must add no arithmetic
//! (a phase sample's pdf and weight are by contract those of the returned world-space `wo` taken
//! back to the local frame, so that `mf_phase_pdf` reproduces them: the core does the same).
//! Also checks the `#[repr(C)]` layouts against the numbers `tests/c/abi_test.c` asserts with
//! `offsetof`, so that both sides of the boundary agree on them.

mod common;

use common::last_error;
use glam::DVec3;
use macrofacet_ffi::*;
use macrofacet::frame::{check_direction, Frame};
use macrofacet::{medium_from_params, FreeFlight, MacrofacetMedium, ParamSet, PhaseSample};
use std::ffi::CString;
use std::mem::{offset_of, size_of};
use std::ptr;

/// splitmix64, uniforms in [0, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    /// A world direction of length 1 within the accepted 1e-6 (not exactly 1: renormalisation
    /// is part of the contract).
    fn direction(&mut self) -> DVec3 {
        let z = 1.0 - 2.0 * self.next();
        let phi = 2.0 * std::f64::consts::PI * self.next();
        let r = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(r * phi.cos(), r * phi.sin(), z) * (1.0 + 4e-7 * (self.next() - 0.5))
    }
    fn frame(&mut self) -> mf_frame {
        if self.next() < 0.25 {
            return mf_frame { normal: v(DVec3::Z), tangent: v(DVec3::X) };
        }
        // Unnormalised normal; a tangent that is not orthogonal (or zero) to it.
        let n = self.direction() * (0.5 + 2.0 * self.next());
        let t = if self.next() < 0.1 { DVec3::ZERO } else { self.direction() };
        mf_frame { normal: v(n), tangent: v(t) }
    }
}

fn v(d: DVec3) -> mf_vec3 {
    mf_vec3 { x: d.x, y: d.y, z: d.z }
}
fn dv(d: mf_vec3) -> DVec3 {
    DVec3::new(d.x, d.y, d.z)
}
fn bits3(c: [f64; 3]) -> [u64; 3] {
    c.map(f64::to_bits)
}
fn rgb_bits(c: mf_rgb) -> [u64; 3] {
    bits3([c.r, c.g, c.b])
}

enum P {
    F(&'static str, f64),
    S(&'static str, &'static str),
    C(&'static str, [f64; 3]),
}

/// The same parameters as an FFI parameter set and as a core one.
fn param_sets(params: &[P]) -> (*mut mf_params, ParamSet) {
    let mut set = ParamSet::new();
    let mut handle: *mut mf_params = ptr::null_mut();
    unsafe {
        assert_eq!(mf_params_new(&mut handle), mf_status::MF_OK);
        for p in params {
            let status = match *p {
                P::F(n, x) => {
                    set.set_float(n, x);
                    mf_params_set_float(handle, CString::new(n).unwrap().as_ptr(), x)
                }
                P::S(n, s) => {
                    set.set_string(n, s);
                    mf_params_set_string(handle, CString::new(n).unwrap().as_ptr(), CString::new(s).unwrap().as_ptr())
                }
                P::C(n, c) => {
                    set.set_rgb(n, c);
                    mf_params_set_rgb(handle, CString::new(n).unwrap().as_ptr(), c.as_ptr())
                }
            };
            assert_eq!(status, mf_status::MF_OK);
        }
    }
    (handle, set)
}

/// The same parameters as an FFI handle and as a core medium.
fn media(params: &[P]) -> (*mut mf_medium, MacrofacetMedium) {
    let (handle, set) = param_sets(params);
    unsafe {
        let mut medium: *mut mf_medium = ptr::null_mut();
        assert_eq!(mf_medium_new(handle, &mut medium), mf_status::MF_OK);
        mf_params_free(handle);
        (medium, medium_from_params(&set).expect("core accepts what the FFI accepted"))
    }
}

fn all_media() -> Vec<(&'static str, Vec<P>)> {
    use P::*;
    vec![
        ("gpss eta/k", vec![F("sigma", 0.5), F("shell_extent", 8.0), F("alpha_u", 0.3), F("alpha_v", 0.6), F("alpha_z", 0.4),
            C("eta", [0.2, 0.9, 1.1]), C("k", [3.9, 2.4, 2.1])]),
        ("gpss kernel Au", vec![F("variance", 0.04), F("lengthscale_x", 0.5), F("lengthscale_y", 0.7), F("lengthscale_z", 1.3),
            S("material", "Au")]),
        ("gpss isotropic mirror", vec![F("sigma", 0.1), F("alpha", 0.5), C("specular_reflectance", [0.9, 0.8, 0.7])]),
        ("gpss mixture Ag", vec![F("sigma", 0.2), F("alpha_u", 0.3), F("alpha_v", 0.5), F("alpha_z", 0.6),
            S("vndf_sampling", "mixture"), F("mixture_ratio", 0.3), S("material", "Ag")]),
        ("gpss height field", vec![F("sigma", 0.2), F("alpha_u", 0.3), F("alpha_v", 0.5), F("alpha_z", 0.0), S("material", "Cr")]),
        ("beckmann Cu", vec![F("sigma", 1.5), S("distribution", "beckmann"), F("alpha_u", 0.2), F("alpha_v", 0.45), S("material", "Cu")]),
        ("ggx Al", vec![F("sigma", 0.05), S("distribution", "ggx"), F("alpha", 0.35), S("material", "Al")]),
        ("ggx kernel", vec![F("sigma", 0.05), S("distribution", "ggx"), F("lengthscale_x", 0.2), F("lengthscale_y", 0.1)]),
        ("gpss diffuse", vec![F("sigma", 0.3), F("alpha", 0.4), S("micro_bsdf", "diffuse"), C("reflectance", [0.2, 0.5, 0.8])]),
        ("beckmann diffuse", vec![F("sigma", 0.3), S("distribution", "beckmann"), F("alpha", 0.6), S("micro_bsdf", "diffuse")]),
        ("gtr Ag", vec![F("sigma", 0.1), S("distribution", "gtr"), F("alpha", 0.3), F("gamma", 1.7), S("material", "Ag")]),
        ("gtr dimov anisotropic", vec![F("sigma", 0.1), S("distribution", "gtr"), F("alpha_u", 0.2), F("alpha_v", 0.5),
            F("gamma", 2.6), S("lambda", "dimov")]),
        ("ggx skewed", vec![F("sigma", 0.2), S("distribution", "ggx"), F("alpha", 0.3), F("transform_xx", 1.0), F("transform_xy", 2.0),
            F("transform_yx", 0.0), F("transform_yy", 1.0), S("material", "Au")]),
        ("gtr stretched appendix b", vec![F("sigma", 0.2), S("distribution", "gtr"), F("alpha", 0.4), F("gamma", 1.2), F("stretch", -0.4),
            S("vndf_sampling", "mixture")]),
    ]
}

/// The FFI's preprocessing of an event, done with the core: the frame, directions to local.
struct Core {
    frame: Frame,
}
impl Core {
    fn new(f: &mf_frame) -> Self {
        Core { frame: Frame::from_normal_tangent(dv(f.normal), dv(f.tangent)).unwrap() }
    }
    fn local(&self, d: mf_vec3) -> DVec3 {
        self.frame.to_local(check_direction("d", dv(d)).unwrap())
    }
    /// A phase sample as the contract defines it: the core's direction taken to world space, and
    /// the pdf and weight of that world direction as `mf_phase_pdf` takes it back to local.
    fn phase_sample(&self, core: &MacrofacetMedium, wi: DVec3, u: [f64; MF_PHASE_SAMPLE_DIMENSIONS]) -> Option<(DVec3, PhaseSample)> {
        let wo = self.frame.to_world(core.phase.sample_direction(wi, u)?);
        Some((wo, core.phase.sample_record(wi, self.local(v(wo)))?))
    }
}

#[test]
fn ffi_queries_equal_the_core_bit_for_bit() {
    let mut rng = Rng(20240607);
    for (name, params) in all_media() {
        let (handle, core) = media(&params);
        let h = handle as *const mf_medium;
        let diffuse = name.contains("diffuse");
        let n = if diffuse { 150 } else { 1500 };
        let sigma = core.height.sigma;
        unsafe {
            let mut top = f64::NAN;
            assert_eq!(mf_medium_shell_top(h, &mut top), mf_status::MF_OK);
            assert_eq!(top.to_bits(), core.height.top().to_bits(), "{name}: shell top");
        }
        for i in 0..n {
            let fr = rng.frame();
            let c = Core::new(&fr);
            let f = sigma * (-4.0 + 9.0 * rng.next());
            let f2 = sigma * (-4.0 + 9.0 * rng.next());
            let d = v(rng.direction());
            let t = match i % 5 {
                0 => f64::INFINITY,
                1 => 0.0,
                _ => 5.0 * sigma * rng.next(),
            };
            let u = rng.next();
            let wi = v(rng.direction());
            let wo = v(rng.direction());
            let us: [f64; MF_PHASE_SAMPLE_DIMENSIONS] = std::array::from_fn(|_| rng.next());
            let (dl, wil, wol) = (c.local(d), c.local(wi), c.local(wo));
            let ctx = format!("{name}, input {i}: f {f} d {d:?} t {t} u {u}");
            unsafe {
                let mut x = f64::NAN;
                assert_eq!(mf_medium_sigma_t(h, &fr, f, d, &mut x), mf_status::MF_OK);
                assert_eq!(x.to_bits(), core.sigma_t(f, dl).to_bits(), "sigma_t: {ctx}");
                assert_eq!(mf_medium_majorant(h, &fr, f, f2, d, &mut x), mf_status::MF_OK);
                assert_eq!(x.to_bits(), core.majorant(f, f2, dl).to_bits(), "majorant: {ctx}");
                assert_eq!(mf_medium_optical_depth(h, &fr, f, d, t, &mut x), mf_status::MF_OK);
                assert_eq!(x.to_bits(), core.optical_depth(f, dl, t).to_bits(), "optical depth: {ctx}");
                assert_eq!(mf_medium_transmittance(h, &fr, f, d, t, &mut x), mf_status::MF_OK);
                assert_eq!(x.to_bits(), core.transmittance(f, dl, t).to_bits(), "transmittance: {ctx}");

                let mut fl = mf_free_flight { scattered: false, t: f64::NAN };
                assert_eq!(mf_medium_sample_free_flight(h, &fr, f, d, t, u, &mut fl), mf_status::MF_OK);
                match core.sample_free_flight(f, dl, t, u) {
                    FreeFlight::Scatter { t: tc } => {
                        assert!(fl.scattered, "free flight scatters: {ctx}");
                        assert_eq!(fl.t.to_bits(), tc.to_bits(), "free flight t: {ctx}");
                    }
                    FreeFlight::Pass => {
                        assert!(!fl.scattered, "free flight passes: {ctx}");
                        assert_eq!(fl.t.to_bits(), t.to_bits(), "pass reports t_max: {ctx}");
                    }
                }

                let mut val = mf_rgb { r: f64::NAN, g: f64::NAN, b: f64::NAN };
                assert_eq!(mf_phase_eval(h, &fr, wi, wo, &mut val), mf_status::MF_OK);
                assert_eq!(rgb_bits(val), bits3(core.phase.eval(wil, wol)), "phase eval: {ctx}");
                assert_eq!(mf_phase_pdf(h, &fr, wi, wo, &mut x), mf_status::MF_OK);
                assert_eq!(x.to_bits(), core.phase.pdf(wil, wol).to_bits(), "phase pdf: {ctx}");

                let mut s = mf_phase_sample_result {
                    wo: mf_vec3 { x: 9.0, y: 9.0, z: 9.0 },
                    weight: mf_rgb { r: 9.0, g: 9.0, b: 9.0 },
                    pdf: 9.0,
                    valid: true,
                };
                assert_eq!(mf_phase_sample(h, &fr, wi, us.as_ptr(), &mut s), mf_status::MF_OK);
                match c.phase_sample(&core, wil, us) {
                    Some((w, cs)) => {
                        assert!(s.valid, "phase sample valid: {ctx}");
                        assert_eq!([s.wo.x, s.wo.y, s.wo.z].map(f64::to_bits), [w.x, w.y, w.z].map(f64::to_bits), "sample wo: {ctx}");
                        assert_eq!(rgb_bits(s.weight), bits3(cs.weight), "sample weight: {ctx}");
                        assert_eq!(s.pdf.to_bits(), cs.pdf.to_bits(), "sample pdf: {ctx}");
                    }
                    None => {
                        assert!(!s.valid, "phase sample invalid: {ctx}");
                        assert_eq!((s.pdf, s.wo.x, s.wo.y, s.wo.z, s.weight.r), (0.0, 0.0, 0.0, 0.0, 0.0), "{ctx}");
                    }
                }
            }
        }
        unsafe { mf_medium_free(handle) };
    }
}

#[test]
fn batches_equal_the_core_bit_for_bit() {
    let mut rng = Rng(77);
    for (name, params) in all_media() {
        let (handle, core) = media(&params);
        let h = handle as *const mf_medium;
        let count = if name.contains("diffuse") { 40 } else { 400 };
        let sigma = core.height.sigma;
        let mut fq = Vec::new();
        let mut pq = Vec::new();
        let mut sq = Vec::new();
        for i in 0..count {
            let frame = rng.frame();
            fq.push(mf_flight_query {
                frame,
                f: sigma * (-4.0 + 9.0 * rng.next()),
                d: v(rng.direction()),
                t_max: if i % 4 == 0 { f64::INFINITY } else { 4.0 * sigma * rng.next() },
                u: rng.next(),
            });
            pq.push(mf_phase_query { frame, wi: v(rng.direction()), wo: v(rng.direction()) });
            sq.push(mf_phase_sample_query { frame, wi: v(rng.direction()), u: std::array::from_fn(|_| rng.next()) });
        }
        let mut tr = vec![f64::NAN; count];
        let mut ff = vec![mf_free_flight { scattered: false, t: f64::NAN }; count];
        let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
        let mut pv = vec![mf_phase_value { value: mf_rgb { r: 0.0, g: 0.0, b: 0.0 }, pdf: f64::NAN }; count];
        let mut ps = vec![mf_phase_sample_result { wo: zero, weight: mf_rgb { r: 0.0, g: 0.0, b: 0.0 }, pdf: f64::NAN, valid: false }; count];
        unsafe {
            assert_eq!(mf_medium_transmittance_batch(h, fq.as_ptr(), count, tr.as_mut_ptr()), mf_status::MF_OK);
            assert_eq!(mf_medium_sample_free_flight_batch(h, fq.as_ptr(), count, ff.as_mut_ptr()), mf_status::MF_OK);
            assert_eq!(mf_phase_eval_batch(h, pq.as_ptr(), count, pv.as_mut_ptr()), mf_status::MF_OK);
            assert_eq!(mf_phase_sample_batch(h, sq.as_ptr(), count, ps.as_mut_ptr()), mf_status::MF_OK);
        }
        for i in 0..count {
            let ctx = format!("{name}, query {i}");
            let q = &fq[i];
            let c = Core::new(&q.frame);
            let dl = c.local(q.d);
            assert_eq!(tr[i].to_bits(), core.transmittance(q.f, dl, q.t_max).to_bits(), "transmittance batch: {ctx}");
            match core.sample_free_flight(q.f, dl, q.t_max, q.u) {
                FreeFlight::Scatter { t } => assert!(ff[i].scattered && ff[i].t.to_bits() == t.to_bits(), "flight batch: {ctx}"),
                FreeFlight::Pass => assert!(!ff[i].scattered && ff[i].t.to_bits() == q.t_max.to_bits(), "flight batch: {ctx}"),
            }
            let c = Core::new(&pq[i].frame);
            let (wi, wo) = (c.local(pq[i].wi), c.local(pq[i].wo));
            assert_eq!(rgb_bits(pv[i].value), bits3(core.phase.eval(wi, wo)), "eval batch: {ctx}");
            assert_eq!(pv[i].pdf.to_bits(), core.phase.pdf(wi, wo).to_bits(), "pdf batch: {ctx}");
            let c = Core::new(&sq[i].frame);
            match c.phase_sample(&core, c.local(sq[i].wi), sq[i].u) {
                Some((w, s)) => {
                    assert!(ps[i].valid, "sample batch valid: {ctx}");
                    assert_eq!([ps[i].wo.x, ps[i].wo.y, ps[i].wo.z].map(f64::to_bits), [w.x, w.y, w.z].map(f64::to_bits), "{ctx}");
                    assert_eq!(rgb_bits(ps[i].weight), bits3(s.weight), "sample batch weight: {ctx}");
                    assert_eq!(ps[i].pdf.to_bits(), s.pdf.to_bits(), "sample batch pdf: {ctx}");
                }
                None => assert!(!ps[i].valid, "sample batch invalid: {ctx}"),
            }
        }
        unsafe { mf_medium_free(handle) };
    }
}

/// The FFI rejects exactly what the core rejects when building, with the matching status.
#[test]
fn construction_errors_map_to_statuses() {
    use P::*;
    let cases: Vec<(Vec<P>, mf_status)> = vec![
        (vec![F("alpha", 0.3)], mf_status::MF_ERROR_MISSING_PARAMETER),
        (vec![F("sigma", -1.0), F("alpha", 0.3)], mf_status::MF_ERROR_INVALID_VALUE),
        (vec![F("sigma", 1.0), F("alpha", 0.3), F("bogus", 1.0)], mf_status::MF_ERROR_UNKNOWN_PARAMETER),
        (vec![S("sigma", "1"), F("alpha", 0.3)], mf_status::MF_ERROR_WRONG_TYPE),
        (vec![F("sigma", 1.0), F("alpha", 0.3), S("distribution", "phong")], mf_status::MF_ERROR_INVALID_VALUE),
        // Issue 9 item 8: parameters whose derived quantities leave the range of f64.
        (vec![F("sigma", 1e308), F("alpha", 0.3)], mf_status::MF_ERROR_INVALID_VALUE),
        (vec![F("variance", 1e300), F("alpha", 0.3)], mf_status::MF_ERROR_INVALID_VALUE),
        (vec![F("sigma", 1.0), F("alpha", 0.3), F("shell_extent", 1e300)], mf_status::MF_ERROR_INVALID_VALUE),
        (vec![F("sigma", 1.0), F("alpha", 1e-9)], mf_status::MF_ERROR_INVALID_VALUE),
        (vec![F("sigma", 1.0), F("lengthscale_x", 1e-300), F("lengthscale_y", 1.0), F("lengthscale_z", 1.0)], mf_status::MF_ERROR_INVALID_VALUE),
    ];
    for (params, want) in cases {
        let mut set = ParamSet::new();
        let mut handle: *mut mf_params = ptr::null_mut();
        unsafe {
            mf_params_new(&mut handle);
            for p in &params {
                match *p {
                    F(n, x) => {
                        set.set_float(n, x);
                        mf_params_set_float(handle, CString::new(n).unwrap().as_ptr(), x);
                    }
                    S(n, s) => {
                        set.set_string(n, s);
                        mf_params_set_string(handle, CString::new(n).unwrap().as_ptr(), CString::new(s).unwrap().as_ptr());
                    }
                    C(n, c) => {
                        set.set_rgb(n, c);
                        mf_params_set_rgb(handle, CString::new(n).unwrap().as_ptr(), c.as_ptr());
                    }
                }
            }
            let sentinel = 0x5EAF00D as *mut mf_medium;
            let mut out = sentinel;
            let status = mf_medium_new(handle, &mut out);
            mf_params_free(handle);
            let core_err = medium_from_params(&set).expect_err("core must reject too");
            assert_eq!(status, want, "status for {:?}", core_err);
            assert_eq!(mf_status::from(core_err.kind), want);
            assert_eq!(out, sentinel, "out_medium written on failure");
            let mut buf = [0u8; 512];
            let mut len = 0usize;
            assert_eq!(mf_last_error_message(buf.as_mut_ptr().cast(), buf.len(), &mut len), mf_status::MF_OK);
            assert_eq!(&buf[..len], core_err.message.as_bytes(), "the FFI message is the core's");
        }
    }
}

/// Layout of the `#[repr(C)]` types: the same numbers tests/c/abi_test.c asserts with offsetof.
#[test]
fn repr_c_layouts_match_the_c_test() {
    assert_eq!((size_of::<mf_vec3>(), offset_of!(mf_vec3, y), offset_of!(mf_vec3, z)), (24, 8, 16));
    assert_eq!((size_of::<mf_rgb>(), offset_of!(mf_rgb, g), offset_of!(mf_rgb, b)), (24, 8, 16));
    assert_eq!((size_of::<mf_frame>(), offset_of!(mf_frame, tangent)), (48, 24));
    assert_eq!((size_of::<mf_free_flight>(), offset_of!(mf_free_flight, t)), (16, 8));
    assert_eq!(
        (size_of::<mf_phase_sample_result>(), offset_of!(mf_phase_sample_result, weight), offset_of!(mf_phase_sample_result, pdf), offset_of!(mf_phase_sample_result, valid)),
        (64, 24, 48, 56)
    );
    assert_eq!(
        (
            size_of::<mf_flight_query>(),
            offset_of!(mf_flight_query, f),
            offset_of!(mf_flight_query, d),
            offset_of!(mf_flight_query, t_max),
            offset_of!(mf_flight_query, u)
        ),
        (96, 48, 56, 80, 88)
    );
    assert_eq!((size_of::<mf_phase_query>(), offset_of!(mf_phase_query, wi), offset_of!(mf_phase_query, wo)), (96, 48, 72));
    assert_eq!((size_of::<mf_phase_value>(), offset_of!(mf_phase_value, pdf)), (32, 24));
    assert_eq!(
        (size_of::<mf_phase_sample_query>(), offset_of!(mf_phase_sample_query, wi), offset_of!(mf_phase_sample_query, u)),
        (112, 48, 72)
    );
    assert_eq!(size_of::<mf_status>(), 4);
}

/// `f = z - 0.25`: a plane for the GPIS trace, counting its calls through `user_data`.
unsafe extern "C" fn plane_sdf(user_data: *mut std::ffi::c_void, p: mf_vec3, out: *mut mf_sdf_sample) {
    *(user_data as *mut usize) += 1;
    *out = mf_sdf_sample { f: p.z - 0.25, gradient: mf_vec3 { x: 0.0, y: 0.0, z: 1.0 }, u: 0.0, v: 0.0 };
}

#[test]
fn gpis_trace_equals_the_core_for_the_same_seed() {
    use macrofacet::field::Constant;
    use macrofacet_gpis::{Plane, StartState, Trace};
    use macrofacet_gpis::gpis_from_params;
    use macrofacet_validation::stats::Pcg32;
    let mut params = ParamSet::new();
    params.set_float("sigma", 0.5).set_float("alpha", 0.8).set_string("memory", "renewal_plus");
    let core = gpis_from_params(&params).unwrap();
    let mut handle: *mut mf_params = ptr::null_mut();
    let mut gpis: *mut mf_gpis = ptr::null_mut();
    unsafe {
        assert_eq!(mf_params_new(&mut handle), mf_status::MF_OK);
        for (name, value) in [("sigma", 0.5), ("alpha", 0.8)] {
            let name = CString::new(name).unwrap();
            assert_eq!(mf_params_set_float(handle, name.as_ptr(), value), mf_status::MF_OK);
        }
        let (name, value) = (CString::new("memory").unwrap(), CString::new("renewal_plus").unwrap());
        assert_eq!(mf_params_set_string(handle, name.as_ptr(), value.as_ptr()), mf_status::MF_OK);
        assert_eq!(mf_gpis_new(handle, &mut gpis), mf_status::MF_OK);
        mf_params_free(handle);
    }
    let mean = Plane { height: 0.25 };
    let mut calls = 0usize;
    let mut hits = 0;
    for seed in 0..200u64 {
        let d = DVec3::new(0.3, -0.2, -0.9).normalize();
        let origin = DVec3::new(0.0, 0.0, 3.0);
        let mut rng = Pcg32::new(seed, 0x6d66_6770_6973);
        // The FFI renormalises d with check_direction; hand the core the same vector.
        let expected = core.trace(&mean, &Constant, origin, check_direction("d", d).unwrap(), f64::INFINITY, &StartState::Uncorrelated, &mut || rng.next_f64()).unwrap();
        let start = mf_gpis_start { kind: MF_GPIS_START_FREE, gradient: v(DVec3::ZERO) };
        let mut hit = mf_gpis_hit { hit: false, t: f64::NAN, point: v(DVec3::ZERO), normal: v(DVec3::ZERO), gradient: v(DVec3::ZERO), local: mf_local_params::NONE };
        let status = unsafe {
            mf_gpis_trace(gpis, Some(plane_sdf), ptr::null(), &mut calls as *mut usize as *mut _, v(origin), v(d), f64::INFINITY, &start, seed, &mut hit)
        };
        assert_eq!(status, mf_status::MF_OK);
        match expected {
            Trace::Hit(c) => {
                hits += 1;
                assert!(hit.hit && hit.t.to_bits() == c.t.to_bits(), "seed {seed}: {hit:?} vs {c:?}");
                assert_eq!(bits3(dv(hit.normal).to_array()), bits3(c.normal.to_array()));
                assert_eq!(bits3(dv(hit.gradient).to_array()), bits3(c.gradient.to_array()));
            }
            _ => assert!(!hit.hit, "seed {seed}: the FFI hit, the core did not"),
        }
    }
    assert!(calls > 0 && hits == 200, "{hits} hits, {calls} callback calls");
    unsafe { mf_gpis_free(gpis) };
}

/// A plane `z = 0.3` (interior below) implemented with C callbacks, for the callback surface.
unsafe extern "C" fn plane_point(_: *mut std::ffi::c_void, p: mf_vec3, out: *mut mf_surface_point) -> i32 {
    unsafe { *out = mf_surface_point { f: p.z - 0.3, normal: v(DVec3::Z), tangent: v(DVec3::X), u: p.x, v: p.y } };
    0
}

/// `mf_track_free_flight`, `mf_track_transmittance` and their batches give exactly what the
/// core `Tracker` gives on the same surface with the documented seed stream, for a sphere, a
/// mesh (with vertex normals) and a host callback surface; the counts agree too.
#[test]
fn tracking_calls_equal_the_core_bit_for_bit() {
    use macrofacet::rng::Pcg32;
    use macrofacet::surface::{MeanSurface, Sphere, TriangleMesh};
    use macrofacet::tracking::{ProjectedAreaBounds, TrackStats, TrackedFlight, Tracker, TRACK_STREAM};

    // An octahedron with vertex normals.
    let positions: Vec<f64> = vec![1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0];
    let indices: Vec<u32> = vec![0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5];
    let (mut sphere_h, mut mesh_h, mut plane_h) = (ptr::null_mut(), ptr::null_mut(), ptr::null_mut());
    let pole = DVec3::new(0.0, 0.6, 0.8);
    let callbacks = mf_surface_callbacks {
        point: Some(plane_point),
        bound: None,
        shape: MF_SURFACE_CONVEX,
        bounds_min: v(DVec3::NEG_INFINITY),
        bounds_max: v(DVec3::new(f64::INFINITY, f64::INFINITY, 0.3)),
    };
    unsafe {
        assert_eq!(mf_surface_new_sphere(v(DVec3::new(0.1, -0.2, 0.3)), 0.9, false, v(pole), &mut sphere_h), mf_status::MF_OK);
        let mesh = mf_mesh { positions: positions.as_ptr(), vertex_count: 6, indices: indices.as_ptr(), triangle_count: 8, normals: positions.as_ptr(), uvs: ptr::null() };
        assert_eq!(mf_surface_new_mesh(&mesh, 1, f64::INFINITY, &mut mesh_h), mf_status::MF_OK);
        assert_eq!(mf_surface_new_callbacks(&callbacks, &mut plane_h), mf_status::MF_OK);
    }
    let sphere = Sphere::new(DVec3::new(0.1, -0.2, 0.3), 0.9, false, pole).unwrap();
    let points: Vec<DVec3> = positions.chunks_exact(3).map(DVec3::from_slice).collect();
    let tris: Vec<[u32; 3]> = indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
    let octahedron = TriangleMesh::new(&points, &tris, Some(&points), None, 1, f64::INFINITY).unwrap();

    fn compare<S: MeanSurface>(name: &str, handle: *const mf_surface, medium: *const mf_medium, core: &MacrofacetMedium, surface: &S, rng: &mut Rng) {
        // The medium's handle holds its bounds built once, with their cells.
        let bounds = ProjectedAreaBounds::of(core);
        let tracker = Tracker::with_bounds(core, &bounds, surface, &macrofacet::field::Constant);
        let mut queries = Vec::new();
        for i in 0..300u64 {
            // Rays from around the shell towards the surface, some leaving it, some unbounded.
            let origin = rng.direction() * (0.6 + 0.8 * rng.next());
            let d = rng.direction().normalize();
            let t_max = if i % 3 == 0 { f64::INFINITY } else { 2.0 * rng.next() };
            queries.push(mf_track_query { origin: v(origin), d: v(d), t_max, seed: i * 7919 + 1, exit_level: 0.0, survival: 0.0, hint: 0 });
        }
        let stats = |s: &TrackStats| mf_track_stats { surface_queries: s.surface_queries, segments: s.segments, tentative_collisions: s.tentative_collisions, majorant_violations: s.majorant_violations };
        let mut flights = vec![unsafe { std::mem::zeroed::<mf_collision>() }; queries.len()];
        let mut shadows = vec![unsafe { std::mem::zeroed::<mf_transmittance>() }; queries.len()];
        unsafe {
            assert_eq!(mf_track_free_flight_batch(medium, handle, ptr::null(), ptr::null_mut(), queries.as_ptr(), queries.len(), flights.as_mut_ptr()), mf_status::MF_OK);
            assert_eq!(mf_track_transmittance_batch(medium, handle, ptr::null(), ptr::null_mut(), queries.as_ptr(), queries.len(), shadows.as_mut_ptr()), mf_status::MF_OK);
        }
        let (mut scattered, mut partial) = (0, 0);
        for (i, q) in queries.iter().enumerate() {
            // The documented preprocessing: the direction checked and renormalised.
            let (o, d) = (dv(q.origin), check_direction("d", dv(q.d)).unwrap());
            let ctx = format!("{name}, query {i}");
            let mut c = unsafe { std::mem::zeroed::<mf_collision>() };
            let mut t = unsafe { std::mem::zeroed::<mf_transmittance>() };
            unsafe {
                assert_eq!(mf_track_free_flight(medium, handle, ptr::null(), ptr::null_mut(), q, &mut c), mf_status::MF_OK, "{ctx}");
                assert_eq!(mf_track_transmittance(medium, handle, ptr::null(), ptr::null_mut(), q, &mut t), mf_status::MF_OK, "{ctx}");
            }
            assert_eq!(c, flights[i], "{ctx}: batch and single free flights differ");
            assert_eq!(t, shadows[i], "{ctx}: batch and single transmittances differ");
            let mut s = TrackStats::default();
            match tracker.sample_free_flight(o, d, q.t_max, &mut Pcg32::new(q.seed, TRACK_STREAM), &mut s).unwrap() {
                TrackedFlight::Scatter { t: tc, point, .. } => {
                    scattered += 1;
                    assert!(c.scattered, "{ctx}: the core scatters");
                    assert_eq!((c.t.to_bits(), c.f.to_bits()), (tc.to_bits(), point.f.to_bits()), "{ctx}: collision");
                    assert_eq!(dv(c.p), o + tc * d, "{ctx}: collision point");
                    assert_eq!((dv(c.frame.normal), dv(c.frame.tangent)), (point.normal, point.tangent), "{ctx}: frame");
                }
                TrackedFlight::Pass => {
                    assert!(!c.scattered, "{ctx}: the core passes");
                    assert_eq!(c.t.to_bits(), q.t_max.to_bits(), "{ctx}: a pass reports t_max");
                }
            }
            assert_eq!(c.stats, stats(&s), "{ctx}: free-flight counts");
            let mut s = TrackStats::default();
            let tc = tracker.transmittance(o, d, q.t_max, &mut Pcg32::new(q.seed, TRACK_STREAM), &mut s).unwrap();
            assert_eq!(t.transmittance.to_bits(), tc.to_bits(), "{ctx}: transmittance");
            assert_eq!(t.stats, stats(&s), "{ctx}: transmittance counts");
            assert_eq!(t.stats.majorant_violations + c.stats.majorant_violations, 0, "{ctx}: violations");
            if tc > 0.0 && tc < 1.0 {
                partial += 1;
            }
        }
        // The rays exercise both outcomes and fractional transmittances (the test can fail).
        assert!(scattered > 30 && scattered < 270, "{name}: {scattered} of 300 scattered");
        assert!(partial > 10, "{name}: only {partial} fractional transmittances");
        // mf_track_opaque_core: the core's levels (−∞ where it has none).
        let (mut start, mut level) = (0.0, 0.0);
        assert_eq!(unsafe { mf_track_opaque_core(medium, handle, &mut start, &mut level) }, mf_status::MF_OK, "{name}");
        let expected = tracker.opaque_core().map_or((-8.0 * core.height.sigma, f64::NEG_INFINITY), |c| (c.start_level, c.core_level));
        assert_eq!((start.to_bits(), level.to_bits()), (expected.0.to_bits(), expected.1.to_bits()), "{name}: opaque core");
        // mf_track_depth_roulette and a kept ray's transmittance (mf_track_query::survival).
        let sigma = core.height.sigma;
        for (f_from, f_to, u) in [(0.0, -0.5 * sigma, 0.3), (sigma, -2.0 * sigma, 0.01), (-sigma, -3.0 * sigma, 1e-4), (0.0, -20.0 * sigma, 0.5), (0.0, sigma, 0.9)] {
            let mut survival = -1.0;
            assert_eq!(unsafe { mf_track_depth_roulette(medium, handle, f_from, f_to, u, &mut survival) }, mf_status::MF_OK, "{name}");
            let expected = tracker.depth_roulette(f_from, f_to, u).unwrap();
            assert_eq!(survival.to_bits(), expected.to_bits(), "{name}: depth roulette ({f_from}, {f_to}, {u})");
            if survival > 0.0 && survival < 1.0 {
                let (o, d) = (DVec3::new(0.0, 0.0, 1.0 + f_from), DVec3::new(1.0, 0.0, -0.2).normalize());
                let q = mf_track_query { origin: v(o), d: v(d), t_max: f64::INFINITY, seed: 17, exit_level: 0.0, survival, hint: 0 };
                let d = check_direction("d", d).unwrap();
                let mut t = unsafe { std::mem::zeroed::<mf_transmittance>() };
                assert_eq!(unsafe { mf_track_transmittance(medium, handle, ptr::null(), ptr::null_mut(), &q, &mut t) }, mf_status::MF_OK, "{name}");
                let kept = Tracker::with_bounds(core, &bounds, surface, &macrofacet::field::Constant).after_roulette(survival).unwrap();
                let tc = kept.transmittance(o, d, f64::INFINITY, &mut Pcg32::new(17, TRACK_STREAM), &mut TrackStats::default()).unwrap();
                assert_eq!(t.transmittance.to_bits(), tc.to_bits(), "{name}: kept transmittance");
            }
        }
    }

    let mut rng = Rng(777);
    for (name, params) in [("thin beckmann", vec![P::F("sigma", 0.02), P::S("distribution", "beckmann"), P::F("alpha_u", 0.2), P::F("alpha_v", 0.4), P::S("material", "Au")]), ("thick gpss", vec![P::F("sigma", 0.15), P::F("alpha", 0.5)])] {
        let (medium, core) = media(&params);
        compare(&format!("{name} sphere"), sphere_h, medium, &core, &sphere, &mut rng);
        compare(&format!("{name} octahedron"), mesh_h, medium, &core, &octahedron, &mut rng);
        let plane = PlaneSurface;
        compare(&format!("{name} callback plane"), plane_h, medium, &core, &plane, &mut rng);
        unsafe { mf_medium_free(medium) };
    }
    unsafe {
        mf_surface_free(sphere_h);
        mf_surface_free(mesh_h);
        mf_surface_free(plane_h);
    }
}

/// The callback plane of [`tracking_calls_equal_the_core_bit_for_bit`] in the core.
struct PlaneSurface;
impl macrofacet::surface::MeanSurface for PlaneSurface {
    type Cache = ();
    fn point(&self, p: DVec3) -> macrofacet::Result<macrofacet::surface::SurfacePoint> {
        Ok(macrofacet::surface::SurfacePoint { f: p.z - 0.3, normal: DVec3::Z, tangent: DVec3::X, uv: glam::DVec2::new(p.x, p.y) })
    }
    fn bound(&self, start: &macrofacet::surface::SurfacePoint, p: DVec3, d: DVec3, length: f64, _: f64, _: &mut ()) -> macrofacet::Result<macrofacet::surface::SegmentBound> {
        let end = self.point(p + length * d)?;
        Ok(macrofacet::surface::convex_bound(start, &end, d, length, macrofacet::surface::Curvature::Convex))
    }
    fn bounding_box(&self) -> macrofacet::surface::Aabb {
        macrofacet::surface::Aabb { min: DVec3::NEG_INFINITY, max: DVec3::new(f64::INFINITY, f64::INFINITY, 0.3) }
    }
}

#[test]
fn ndf_calls_equal_the_core_bit_for_bit() {
    use macrofacet::ndf::MicrofacetDistribution;
    let cases: Vec<Vec<P>> = {
        use P::*;
        vec![
            vec![S("distribution", "gtr"), F("alpha", 0.3), F("gamma", 1.5)],
            vec![S("distribution", "gtr"), F("alpha_u", 0.1), F("alpha_v", 0.4), F("gamma", 3.0), S("lambda", "dimov"), F("stretch", 0.3)],
            vec![S("distribution", "ggx"), F("alpha", 0.2), F("transform_xx", 0.7), F("transform_xy", 0.9), F("transform_yx", -0.4), F("transform_yy", 1.3)],
            vec![F("alpha_u", 0.3), F("alpha_v", 0.2)], // beckmann, the default
        ]
    };
    let mut rng = Rng(777);
    for params in cases {
        let (handle, set) = param_sets(&params);
        let mut ndf: *mut mf_ndf = ptr::null_mut();
        unsafe {
            assert_eq!(mf_ndf_new(handle, &mut ndf), mf_status::MF_OK);
            mf_params_free(handle);
        }
        let core = macrofacet::params::ndf_from_params(&set).unwrap();
        for _ in 0..200 {
            let f = rng.frame();
            let c = Core::new(&f);
            let (wi, m) = (v(rng.direction()), v(rng.direction()));
            let u = [rng.next(), rng.next(), rng.next()];
            let (mut d, mut lambda, mut pdf) = (0.0, 0.0, 0.0);
            let mut s = mf_ndf_sample { m: v(DVec3::ZERO), pdf: 0.0, valid: false };
            unsafe {
                assert_eq!(mf_ndf_eval(ndf, &f, m, &mut d), mf_status::MF_OK);
                assert_eq!(mf_ndf_lambda(ndf, &f, wi, &mut lambda), mf_status::MF_OK);
                assert_eq!(mf_ndf_pdf_visible(ndf, &f, wi, m, &mut pdf), mf_status::MF_OK);
                assert_eq!(mf_ndf_sample_visible(ndf, &f, wi, u.as_ptr(), &mut s), mf_status::MF_OK);
            }
            let (wl, ml) = (c.local(wi), c.local(m));
            assert_eq!(d.to_bits(), core.d(ml).to_bits());
            assert_eq!(lambda.to_bits(), core.lambda(wl).to_bits());
            assert_eq!(pdf.to_bits(), core.pdf_visible(wl, ml).to_bits());
            match core.sample_visible(wl, u) {
                Some(ms) => {
                    // The contract: the core's normal taken to world space, and the density of
                    // that world normal as mf_ndf_pdf_visible takes it back to local.
                    assert!(s.valid);
                    assert_eq!(bits3(dv(s.m).to_array()), bits3(c.frame.to_world(ms).to_array()));
                    assert_eq!(s.pdf.to_bits(), core.pdf_visible(wl, c.local(s.m)).to_bits());
                }
                None => assert!(!s.valid && s.pdf == 0.0),
            }
        }
        unsafe { mf_ndf_free(ndf) };
    }
}
/// A medium from float and string parameters (the issue's cases), as a C host builds it.
fn ffi_medium(floats: &[(&str, f64)], strings: &[(&str, &str)]) -> *mut mf_medium {
    let mut handle: *mut mf_params = ptr::null_mut();
    let mut medium: *mut mf_medium = ptr::null_mut();
    unsafe {
        assert_eq!(mf_params_new(&mut handle), mf_status::MF_OK);
        for (n, x) in floats {
            assert_eq!(mf_params_set_float(handle, CString::new(*n).unwrap().as_ptr(), *x), mf_status::MF_OK);
        }
        for (n, s) in strings {
            let (n, s) = (CString::new(*n).unwrap(), CString::new(*s).unwrap());
            assert_eq!(mf_params_set_string(handle, n.as_ptr(), s.as_ptr()), mf_status::MF_OK);
        }
        assert_eq!(mf_medium_new(handle, &mut medium), mf_status::MF_OK);
        mf_params_free(handle);
    }
    medium
}

fn ffi_sample(m: *const mf_medium, frame: &mf_frame, wi: DVec3, u: [f64; MF_PHASE_SAMPLE_DIMENSIONS]) -> mf_phase_sample_result {
    let mut s = mf_phase_sample_result { wo: v(DVec3::ZERO), weight: mf_rgb { r: 0.0, g: 0.0, b: 0.0 }, pdf: 0.0, valid: false };
    assert_eq!(unsafe { mf_phase_sample(m, frame, v(wi), u.as_ptr(), &mut s) }, mf_status::MF_OK);
    s
}

/// Issue 9 items 1, 5 and 7 through the ABI: a valid sample has a finite weight equal to
/// eval/pdf, a unit `wo` that `mf_phase_eval` accepts, and `mf_phase_pdf(frame, wi, wo)` is its
/// pdf bit for bit — with the issue's media, frames and directions.
#[test]
fn issue9_phase_samples_are_consistent_through_the_abi() {
    let identity = mf_frame { normal: v(DVec3::Z), tangent: v(DVec3::X) };
    // Item 5: a normal of length ~1e-159 (accepted, and now an orthonormal frame).
    let tiny = mf_frame { normal: v(DVec3::new(3e-160, 2e-160, 7e-160)), tangent: v(DVec3::new(1.0, 0.0, 0.0)) };
    let cases: Vec<(&str, *mut mf_medium, DVec3)> = vec![
        ("item 1, alpha 0.3", ffi_medium(&[("sigma", 1.0), ("alpha_u", 0.3), ("alpha_v", 0.3), ("alpha_z", 0.0)], &[("vndf_sampling", "mixture")]), DVec3::new(0.79, 0.0, -0.60)),
        ("item 1, alpha 1e-6", ffi_medium(&[("sigma", 1.0), ("alpha_u", 1e-6), ("alpha_v", 1e-6), ("alpha_z", 0.0)], &[("vndf_sampling", "mixture")]), DVec3::new(0.79, 0.0, -0.60)),
        ("item 5", ffi_medium(&[("sigma", 1.0), ("alpha", 0.3)], &[]), DVec3::new(0.3, 0.2, 0.9)),
        ("item 7", ffi_medium(&[("sigma", 1.0), ("alpha", 1e-6), ("alpha_z", 1e4)], &[]), DVec3::new(0.3, -0.5, 0.4)),
        ("diffuse", ffi_medium(&[("sigma", 1.0), ("alpha", 1000.0)], &[("distribution", "beckmann"), ("micro_bsdf", "diffuse")]), DVec3::new(-0.88, -0.18, -0.43)),
    ];
    let mut rng = Rng(9);
    for (name, m, wi_hint) in cases {
        let mut valid = 0;
        for i in 0..4000 {
            let frame = match i % 3 {
                0 => identity,
                1 => tiny,
                _ => rng.frame(),
            };
            // The issue's direction (normalised), or a random one every other time.
            let wi = if i % 2 == 0 { wi_hint.normalize() } else { rng.direction() };
            let u: [f64; MF_PHASE_SAMPLE_DIMENSIONS] = std::array::from_fn(|_| rng.next());
            let s = ffi_sample(m, &frame, wi, u);
            if !s.valid {
                continue;
            }
            valid += 1;
            let wo = dv(s.wo);
            assert!((wo.length() - 1.0).abs() < 1e-14, "{name}: |wo| = {}", wo.length());
            let (mut pdf, mut value) = (f64::NAN, mf_rgb { r: f64::NAN, g: f64::NAN, b: f64::NAN });
            unsafe {
                assert_eq!(mf_phase_pdf(m, &frame, v(wi), s.wo, &mut pdf), mf_status::MF_OK, "{name}");
                assert_eq!(mf_phase_eval(m, &frame, v(wi), s.wo, &mut value), mf_status::MF_OK, "{name}");
            }
            assert_eq!(pdf.to_bits(), s.pdf.to_bits(), "{name}: sampled pdf vs mf_phase_pdf");
            assert!(pdf > 0.0 && pdf.is_finite(), "{name}: {s:?}");
            for (w, e) in [(s.weight.r, value.r), (s.weight.g, value.g), (s.weight.b, value.b)] {
                assert!(w.is_finite() && (w - e / pdf).abs() <= 1e-12 * w.abs().max(e / pdf), "{name}: weight {w} vs eval/pdf {}", e / pdf);
            }
        }
        assert!(valid > 500 || name == "item 1, alpha 1e-6", "{name}: only {valid} valid samples");
        unsafe { mf_medium_free(m) };
    }
}

/// A plane SDF (as `plane_sdf`) that answers NaN from call `user_data.1` on.
unsafe extern "C" fn failing_sdf(user_data: *mut std::ffi::c_void, p: mf_vec3, out: *mut mf_sdf_sample) {
    let state = &mut *(user_data as *mut (usize, usize));
    state.0 += 1;
    let f = if state.0 > state.1 { f64::NAN } else { p.z - 0.25 };
    *out = mf_sdf_sample { f, gradient: mf_vec3 { x: 0.0, y: 0.0, z: 1.0 }, u: 0.0, v: 0.0 };
}

fn ffi_gpis(floats: &[(&str, f64)], memory: &str) -> Result<*mut mf_gpis, (mf_status, String)> {
    let mut handle: *mut mf_params = ptr::null_mut();
    let sentinel = 0x5EAF00D as *mut mf_gpis;
    let mut gpis = sentinel;
    unsafe {
        assert_eq!(mf_params_new(&mut handle), mf_status::MF_OK);
        for (n, x) in floats {
            assert_eq!(mf_params_set_float(handle, CString::new(*n).unwrap().as_ptr(), *x), mf_status::MF_OK);
        }
        let (n, s) = (CString::new("memory").unwrap(), CString::new(memory).unwrap());
        assert_eq!(mf_params_set_string(handle, n.as_ptr(), s.as_ptr()), mf_status::MF_OK);
        let status = mf_gpis_new(handle, &mut gpis);
        mf_params_free(handle);
        if status == mf_status::MF_OK {
            return Ok(gpis);
        }
        assert_eq!(gpis, sentinel, "out_gpis written on failure");
        Err((status, last_error()))
    }
}

fn ffi_trace(
    gpis: *const mf_gpis,
    sdf: mf_sdf_fn,
    state: *mut std::ffi::c_void,
    origin: DVec3,
    d: DVec3,
    start: mf_gpis_start,
    seed: u64,
) -> (mf_status, mf_gpis_hit) {
    let sentinel = mf_gpis_hit { hit: true, t: -7.0, point: v(DVec3::ONE), normal: v(DVec3::ONE), gradient: v(DVec3::ONE), local: mf_local_params::NONE };
    let mut hit = sentinel;
    let status = unsafe { mf_gpis_trace(gpis, sdf, ptr::null(), state, v(origin), v(d), f64::INFINITY, &start, seed, &mut hit) };
    if status != mf_status::MF_OK {
        assert_eq!(hit, sentinel, "out_hit written on failure");
    }
    (status, hit)
}

/// Issue 9 items 6, 8, 12 and 13 through the ABI.
#[test]
fn issue9_gpis_cases_through_the_abi() {
    // Item 8 and 13: sigma = 1e308 and alpha = 1e5 are refused, naming what to change.
    let (status, message) = ffi_gpis(&[("sigma", 1e308), ("alpha", 0.5)], "renewal").unwrap_err();
    assert!(status == mf_status::MF_ERROR_INVALID_VALUE && message.contains("\"sigma\""), "{message}");
    let (status, message) = ffi_gpis(&[("sigma", 1.0), ("alpha", 1e5)], "renewal").unwrap_err();
    assert!(status == mf_status::MF_ERROR_INVALID_VALUE && message.contains("samples") && message.contains("step_correlation"), "{message}");

    let gpis = ffi_gpis(&[("sigma", 1.0), ("alpha", 0.5)], "renewal_plus").unwrap();
    let on_surface = |g: DVec3| mf_gpis_start { kind: MF_GPIS_START_ON_SURFACE, gradient: v(g) };
    // Item 6: an on-surface start with d . gradient < 0 hit at t = 0 every time.
    let mut calls = 0usize;
    for seed in 0..300 {
        let (status, hit) = ffi_trace(gpis, Some(plane_sdf), &mut calls as *mut usize as *mut _, DVec3::new(0.0, 0.0, 0.25), DVec3::new(0.6, 0.0, -0.8), on_surface(DVec3::Z), seed);
        assert_eq!(status, mf_status::MF_OK);
        assert!(hit.hit && hit.t > 0.0 && hit.t < 1e-2, "seed {seed}: {hit:?}");
    }
    // Item 12: a callback answering NaN is rejected within a few calls of the first NaN
    // (400 004 calls before), from both kinds of start.
    for nan_after in [0usize, 1, 3, 10] {
        for (origin, start) in [
            (DVec3::new(0.0, 0.0, 5.0), mf_gpis_start { kind: MF_GPIS_START_FREE, gradient: v(DVec3::ZERO) }),
            (DVec3::new(0.0, 0.0, 0.25), on_surface(DVec3::Z)),
        ] {
            let mut state = (0usize, nan_after);
            let (status, hit) = ffi_trace(gpis, Some(failing_sdf), &mut state as *mut (usize, usize) as *mut _, origin, DVec3::new(0.3, 0.0, -0.9).normalize(), start, 1);
            if state.0 > nan_after {
                assert_eq!(status, mf_status::MF_ERROR_INVALID_ARGUMENT, "NaN after {nan_after}: {hit:?}");
                assert!(last_error().contains("sdf callback"), "{}", last_error());
                assert!(state.0 - nan_after <= 5, "NaN after {nan_after}: {} calls", state.0);
            } else {
                assert_eq!(status, mf_status::MF_OK);
            }
        }
    }
    // Item 12: a start gradient with a DBL_MAX component is refused after one callback call.
    let mut state = (0usize, usize::MAX);
    let (status, _) = ffi_trace(gpis, Some(failing_sdf), &mut state as *mut (usize, usize) as *mut _, DVec3::new(0.0, 0.0, 0.25), DVec3::Z, on_surface(DVec3::new(f64::MAX, 0.0, 1.0)), 1);
    assert_eq!(status, mf_status::MF_ERROR_INVALID_ARGUMENT);
    assert!(last_error().contains("start.gradient") && state.0 == 1, "{} calls: {}", state.0, last_error());
    unsafe { mf_gpis_free(gpis) };
}

/// Found by fuzzing (target `phase`): the seeds/000 Eq. 40 mixture at grazing incidence (a frame normal of
/// length 1e308, now accepted) with `u = 0` samples a normal at `wi·m ≈ 1e-310`, whose density
/// `(1 − R)/(2π · 4 wi·m)` overflows: a valid sample had `pdf = inf`. Such a sample has weight 0
/// and is not returned.
#[test]
fn fuzz_mixture_samples_with_overflowing_pdf_are_not_returned() {
    let m = ffi_medium(&[("sigma", 3.0), ("lengthscale", 1.000000000001e4), ("mixture_ratio", 8.499862859600035e-5)], &[("vndf_sampling", "mixture")]);
    let frame = mf_frame {
        normal: mf_vec3 { x: 1e-6, y: -9.999999999997382e307, z: -3.255287074942678e-82 },
        tangent: mf_vec3 { x: 1e-6, y: -9.999999999997382e307, z: -3.255287074942678e-82 },
    };
    let wi = DVec3::new(2.2609712140232665e-5, 0.0, 0.9999999997444005);
    let s = ffi_sample(m, &frame, wi, [0.0; MF_PHASE_SAMPLE_DIMENSIONS]);
    assert!(!s.valid || (s.pdf.is_finite() && s.pdf > 0.0), "{s:?}");
    unsafe { mf_medium_free(m) };
}

/// The fuzz target's plane (`normal . p - offset`), answering NaN from call `good + 1` on: in the
/// value on even calls, in the gradient's y on odd ones.
unsafe extern "C" fn alternating_nan_plane(user_data: *mut std::ffi::c_void, p: mf_vec3, out: *mut mf_sdf_sample) {
    let state = &mut *(user_data as *mut (usize, usize));
    state.0 += 1;
    let n = DVec3::new(0.9099771102496692, -0.04040297035089292, -0.41268542354738713);
    let (mut f, mut g) = (n.dot(dv(p)) + 5.999908447265615e50, n);
    if state.0 > state.1 {
        if state.0 % 2 == 0 {
            f = f64::NAN;
        } else {
            g.y = f64::NAN;
        }
    }
    *out = mf_sdf_sample { f, gradient: v(g), u: 0.0, v: 0.0 };
}

/// Found by fuzzing (target `gpis`): a NaN that reached the march only as the prior mean of a
/// conditioning value (the origin's, with the ray then ending at `t_max`) was ignored: MF_OK.
#[test]
fn fuzz_a_nan_mean_anywhere_fails_the_trace() {
    let gpis = ffi_gpis(&[("sigma", 1e50), ("alpha", 10.0)], "renewal").unwrap();
    let origin = DVec3::new(2.5941180484075706e47, -1.1522552036897194e46, 6.177765775644404e47);
    let start = mf_gpis_start { kind: MF_GPIS_START_FREE, gradient: v(DVec3::ZERO) };
    let mut state = (0usize, 5usize);
    let hit_sentinel = mf_gpis_hit { hit: true, t: -7.0, point: v(DVec3::ONE), normal: v(DVec3::ONE), gradient: v(DVec3::ONE), local: mf_local_params::NONE };
    let mut hit = hit_sentinel;
    let status = unsafe {
        mf_gpis_trace(gpis, Some(alternating_nan_plane), ptr::null(), &mut state as *mut (usize, usize) as *mut _, v(origin), v(DVec3::Y), 9.858706006832666, &start, 970143228277, &mut hit)
    };
    assert!(state.0 > 5, "the callback must have answered NaN ({} calls)", state.0);
    assert_eq!(status, mf_status::MF_ERROR_INVALID_ARGUMENT, "{hit:?}");
    assert_eq!(hit, hit_sentinel);
    unsafe { mf_gpis_free(gpis) };
}
