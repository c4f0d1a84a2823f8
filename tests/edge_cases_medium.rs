//! Issue 9 item 2: a segment parallel to the shell, above its top, with `t_max = +inf`
//! (σ = 1, α = 0.3, n = +z, d = (1, 0, 0), f = 3.5, where σ_t = 0): `optical_depth` was inf,
//! `transmittance` 0 and `sample_free_flight` scattered at `t = −inf`; with `t_max = 1e10` all
//! three were right. The free-flight code is being rewritten (issue 8); un-ignore with it.

use glam::DVec3;
use macrofacet::ffi::*;
use macrofacet::{medium_from_params, FreeFlight, ParamSet};
use std::ffi::CString;
use std::ptr;

#[test]
#[ignore = "fixed by the tracking rewrite (lead)"]
fn item2_segment_above_the_shell_parallel_to_it_passes() {
    let mut params = ParamSet::new();
    params.set_float("sigma", 1.0).set_float("alpha", 0.3);
    let medium = medium_from_params(&params).unwrap();
    let d = DVec3::X;
    for t_max in [1e10, f64::INFINITY] {
        assert_eq!(medium.sigma_t(3.5, d), 0.0);
        assert_eq!(medium.optical_depth(3.5, d, t_max), 0.0, "t_max {t_max}");
        assert_eq!(medium.transmittance(3.5, d, t_max), 1.0, "t_max {t_max}");
        for u in [0.0, 0.3, 0.999] {
            assert_eq!(medium.sample_free_flight(3.5, d, t_max, u), FreeFlight::Pass, "t_max {t_max}, u {u}");
        }
    }

    // The same through the C ABI.
    let mut handle: *mut mf_params = ptr::null_mut();
    let mut m: *mut mf_medium = ptr::null_mut();
    unsafe {
        assert_eq!(mf_params_new(&mut handle), mf_status::MF_OK);
        for (name, value) in [("sigma", 1.0), ("alpha", 0.3)] {
            assert_eq!(mf_params_set_float(handle, CString::new(name).unwrap().as_ptr(), value), mf_status::MF_OK);
        }
        assert_eq!(mf_medium_new(handle, &mut m), mf_status::MF_OK);
        mf_params_free(handle);
        let frame = mf_frame { normal: mf_vec3 { x: 0.0, y: 0.0, z: 1.0 }, tangent: mf_vec3 { x: 1.0, y: 0.0, z: 0.0 } };
        let d = mf_vec3 { x: 1.0, y: 0.0, z: 0.0 };
        let (mut tau, mut transmittance) = (f64::NAN, f64::NAN);
        let mut flight = mf_free_flight { scattered: true, t: f64::NAN };
        assert_eq!(mf_medium_optical_depth(m, &frame, 3.5, d, f64::INFINITY, &mut tau), mf_status::MF_OK);
        assert_eq!(mf_medium_transmittance(m, &frame, 3.5, d, f64::INFINITY, &mut transmittance), mf_status::MF_OK);
        assert_eq!(mf_medium_sample_free_flight(m, &frame, 3.5, d, f64::INFINITY, 0.5, &mut flight), mf_status::MF_OK);
        assert_eq!((tau, transmittance), (0.0, 1.0));
        assert!(!flight.scattered && flight.t == f64::INFINITY, "{flight:?}");
        mf_medium_free(m);
    }
}
