//! Construction by named parameters: every accepted form, and every bad input an error (never a
//! panic) whose message names the parameter.

use macrofacet::ndf::{MicrofacetDistribution, Ndf};
use macrofacet::{medium_from_params, ErrorKind, MicroBsdf, ParamSet, VndfSampling};

/// A parameter set that must be rejected: its entries, the error kind, and what the message names.
type RejectedCase = (&'static [(&'static str, &'static str)], ErrorKind, &'static str);

fn params(entries: &[(&str, &str)]) -> ParamSet {
    let mut p = ParamSet::new();
    for (name, value) in entries {
        match value.parse::<f64>() {
            Ok(x) => p.set_float(name, x),
            Err(_) => p.set_string(name, value),
        };
    }
    p
}

#[test]
fn roughness_and_kernel_forms_agree() {
    let by_alpha = medium_from_params(&params(&[("sigma", "0.1"), ("alpha_u", "0.5"), ("alpha_v", "0.25"), ("alpha_z", "1")])).unwrap();
    // alpha = √2 σ / l  =>  l = √2 σ / alpha
    let l = |a: f64| std::f64::consts::SQRT_2 * 0.1 / a;
    let by_kernel = medium_from_params(&params(&[
        ("variance", "0.01"),
        ("lengthscale_x", &l(0.5).to_string()),
        ("lengthscale_y", &l(0.25).to_string()),
        ("lengthscale_z", &l(1.0).to_string()),
    ]))
    .unwrap();
    let (Ndf::Gpss(a), Ndf::Gpss(b)) = (by_alpha.phase.ndf, by_kernel.phase.ndf) else { panic!("gpss expected") };
    assert!((a.alpha_x - b.alpha_x).abs() < 1e-12 && (a.alpha_y - b.alpha_y).abs() < 1e-12 && (a.alpha_z - b.alpha_z).abs() < 1e-12);
    assert!((by_kernel.height.sigma - 0.1).abs() < 1e-15);
}

#[test]
fn defaults_and_presets() {
    let m = medium_from_params(&params(&[("sigma", "1"), ("alpha", "0.3")])).unwrap();
    assert_eq!(m.height.shell_extent, 3.0);
    let Ndf::Gpss(g) = m.phase.ndf else { panic!() };
    assert_eq!((g.alpha_x, g.alpha_y, g.alpha_z), (0.3, 0.3, 0.3), "alpha alone is an isotropic kernel");
    assert!(matches!(m.phase.micro_bsdf, MicroBsdf::Mirror { .. }));
    assert_eq!(m.phase.sampling, VndfSampling::Exact);

    let m = medium_from_params(&params(&[("sigma", "1"), ("alpha", "0.3"), ("distribution", "ggx"), ("material", "Au")])).unwrap();
    assert!(matches!(m.phase.ndf, Ndf::Ggx(_)));
    let MicroBsdf::Conductor { eta, .. } = m.phase.micro_bsdf else { panic!() };
    assert_eq!(eta, macrofacet::fresnel::conductor_preset("Au").unwrap().eta);

    let mut p = params(&[("sigma", "1"), ("alpha", "0.3"), ("micro_bsdf", "diffuse")]);
    p.set_rgb("reflectance", [0.2, 0.4, 0.6]);
    let m = medium_from_params(&p).unwrap();
    assert_eq!(m.phase.micro_bsdf, MicroBsdf::Diffuse { reflectance: [0.2, 0.4, 0.6] });

    let m = medium_from_params(&params(&[("sigma", "1"), ("alpha_u", "0.3"), ("alpha_v", "0.3"), ("alpha_z", "0"), ("vndf_sampling", "mixture"), ("mixture_ratio", "0.7")])).unwrap();
    assert!(matches!(m.phase.sampling, VndfSampling::Mixture(mix) if mix.ratio == 0.7));
    assert!(m.phase.ndf.projected_area(glam::DVec3::Z) > 0.99);
}

#[test]
fn bad_parameters_are_errors_naming_the_parameter() {
    let cases: &[RejectedCase] = &[
        (&[("alpha", "0.3")], ErrorKind::MissingParameter, "sigma"),
        (&[("sigma", "-1"), ("alpha", "0.3")], ErrorKind::InvalidValue, "sigma"),
        (&[("sigma", "NaN"), ("alpha", "0.3")], ErrorKind::InvalidValue, "sigma"),
        (&[("sigma", "inf"), ("alpha", "0.3")], ErrorKind::InvalidValue, "sigma"),
        (&[("sigma", "1"), ("alpha", "-0.3")], ErrorKind::InvalidValue, "alpha"),
        (&[("sigma", "1"), ("alpha", "NaN")], ErrorKind::InvalidValue, "alpha"),
        (&[("sigma", "1"), ("alpha", "0")], ErrorKind::InvalidValue, "alpha"),
        (&[("sigma", "1"), ("alpha", "0.3"), ("distribution", "phong")], ErrorKind::InvalidValue, "distribution"),
        (&[("sigma", "1"), ("alpha", "0.3"), ("material", "Unobtainium")], ErrorKind::InvalidValue, "material"),
        (&[("sigma", "1"), ("alpha", "0.3"), ("micro_bsdf", "plastic")], ErrorKind::InvalidValue, "micro_bsdf"),
        (&[("sigma", "1"), ("alpha", "0.3"), ("colour", "1")], ErrorKind::UnknownParameter, "colour"),
        (&[("sigma", "1"), ("alpha", "0.3"), ("distribution", "ggx"), ("alpha_z", "1")], ErrorKind::UnknownParameter, "alpha_z"),
        (&[("sigma", "1"), ("alpha_u", "0.3"), ("alpha_v", "0.3")], ErrorKind::MissingParameter, "alpha_z"),
        (&[("sigma", "1"), ("alpha", "0.3"), ("lengthscale", "1")], ErrorKind::MissingParameter, "lengthscale"),
        (&[("sigma", "1"), ("variance", "1"), ("alpha", "0.3")], ErrorKind::MissingParameter, "variance"),
        (&[("sigma", "1"), ("alpha", "0.3"), ("shell_extent", "0")], ErrorKind::InvalidValue, "shell_extent"),
        // Height fields take seeds/001 Appendix B's mixture (see below), diffuse flakes none.
        (&[("sigma", "1"), ("alpha", "0.3"), ("distribution", "ggx"), ("vndf_sampling", "mixture"), ("micro_bsdf", "diffuse")], ErrorKind::InvalidValue, "mixture"),
        (&[("sigma", "1"), ("alpha", "0.3"), ("distribution", "ggx"), ("vndf_sampling", "mixture"), ("mixture_ratio", "0")], ErrorKind::InvalidValue, "mixture_ratio"),
        (&[("sigma", "1"), ("alpha", "0.3"), ("vndf_sampling", "mixture"), ("mixture_ratio", "1")], ErrorKind::InvalidValue, "mixture_ratio"),
        (&[("sigma", "1"), ("alpha", "0.3"), ("specular_reflectance", "1.5")], ErrorKind::InvalidValue, "specular_reflectance"),
        (&[("sigma", "1"), ("alpha", "0.3"), ("eta", "1.5")], ErrorKind::MissingParameter, "k"),
        (&[("sigma", "1"), ("alpha", "0.3"), ("material", "Au"), ("eta", "1.5"), ("k", "1")], ErrorKind::MissingParameter, "material"),
        (&[("sigma", "one"), ("alpha", "0.3")], ErrorKind::WrongType, "sigma"),
    ];
    for (entries, kind, named) in cases {
        let err = medium_from_params(&params(entries)).expect_err(&format!("{entries:?} must be rejected"));
        assert_eq!(err.kind, *kind, "{entries:?}: {err}");
        assert!(err.message.contains(named), "{entries:?}: message \"{err}\" does not name {named}");
    }
}

#[test]
fn frame_rejects_bad_vectors_and_round_trips() {
    use glam::DVec3;
    use macrofacet::frame::Frame;
    assert!(Frame::from_normal_tangent(DVec3::ZERO, DVec3::X).is_err());
    assert!(Frame::from_normal_tangent(DVec3::new(f64::NAN, 0.0, 1.0), DVec3::X).is_err());
    let f = Frame::from_normal_tangent(DVec3::new(0.0, 1.0, 1.0), DVec3::new(0.0, 1.0, 1.0)).unwrap(); // tangent ∥ normal
    let v = DVec3::new(0.3, -0.2, 0.9);
    assert!((f.to_world(f.to_local(v)) - v).length() < 1e-14);
    assert!((f.to_local(f.n) - DVec3::Z).length() < 1e-14);
}

#[test]
fn gtr_and_microsurface_transforms_by_name() {
    use macrofacet::ndf::{GtrLambda, LtmdBase};
    let m = medium_from_params(&params(&[("sigma", "0.1"), ("distribution", "gtr"), ("alpha", "0.3"), ("gamma", "1.7")])).unwrap();
    let Ndf::Gtr(g) = m.phase.ndf else { panic!("isotropic gtr is Ndf::Gtr") };
    assert_eq!((g.alpha, g.gamma, g.lambda), (0.3, 1.7, GtrLambda::Exact));
    // Anisotropic GTR: the isotropic GTR of sqrt(α_u α_v) under diag(α/α_u, α/α_v) (seeds/001 Eq. 29).
    let m = medium_from_params(&params(&[("sigma", "0.1"), ("distribution", "gtr"), ("alpha_u", "0.2"), ("alpha_v", "0.8"),
        ("gamma", "2.5"), ("lambda", "dimov")])).unwrap();
    let Ndf::Ltmd(l) = m.phase.ndf else { panic!("anisotropic gtr is a transform") };
    let LtmdBase::Gtr(g) = l.base else { panic!() };
    assert!((g.alpha - 0.4).abs() < 1e-15 && g.lambda == GtrLambda::Dimov);
    assert!((l.transform.x_axis.x - 2.0).abs() < 1e-15 && (l.transform.y_axis.y - 0.5).abs() < 1e-15);
    // γ = 2 anisotropic equals anisotropic GGX.
    let gtr2 = medium_from_params(&params(&[("sigma", "0.1"), ("distribution", "gtr"), ("alpha_u", "0.2"), ("alpha_v", "0.8"), ("gamma", "2")])).unwrap();
    let ggx = medium_from_params(&params(&[("sigma", "0.1"), ("distribution", "ggx"), ("alpha_u", "0.2"), ("alpha_v", "0.8")])).unwrap();
    let w = glam::DVec3::new(0.3, -0.5, 0.2).normalize();
    assert!((gtr2.sigma(w) - ggx.sigma(w)).abs() < 1e-12 * ggx.sigma(w));
    // Stretch and the full matrix, on every height field; Appendix B mixture.
    for dist in ["beckmann", "ggx", "gtr"] {
        let m = medium_from_params(&params(&[("sigma", "0.1"), ("distribution", dist), ("alpha", "0.3"), ("gamma", "1.5"), ("stretch", "0.4")]).tap_gamma(dist)).unwrap();
        assert!(matches!(m.phase.ndf, Ndf::Ltmd(_)), "{dist}");
        let m = medium_from_params(&params(&[("sigma", "0.1"), ("distribution", dist), ("alpha", "0.3"), ("gamma", "1.5"), ("transform_xx", "1"),
            ("transform_xy", "2"), ("transform_yx", "0"), ("transform_yy", "1"), ("vndf_sampling", "mixture")]).tap_gamma(dist)).unwrap();
        assert!(matches!(m.phase.sampling, VndfSampling::NormalMixture(_)), "{dist}");
    }
}

/// `gamma` only for `gtr`: drop it from the set for the other distributions.
trait TapGamma {
    fn tap_gamma(self, dist: &str) -> Self;
}
impl TapGamma for ParamSet {
    fn tap_gamma(self, dist: &str) -> Self {
        if dist == "gtr" {
            return self;
        }
        let mut p = ParamSet::new();
        for name in self.names().filter(|n| *n != "gamma") {
            p.set(name, self.get(name).unwrap().clone());
        }
        p
    }
}

#[test]
fn gtr_and_transform_errors_name_the_parameter() {
    let cases: &[RejectedCase] = &[
        (&[("sigma", "0.1"), ("distribution", "gtr"), ("alpha", "0.3")], ErrorKind::MissingParameter, "\"gamma\""),
        (&[("sigma", "0.1"), ("distribution", "gtr"), ("alpha", "0.3"), ("gamma", "0")], ErrorKind::InvalidValue, "\"gamma\""),
        (&[("sigma", "0.1"), ("distribution", "gtr"), ("alpha", "0.3"), ("gamma", "4.01")], ErrorKind::InvalidValue, "\"gamma\""),
        (&[("sigma", "0.1"), ("distribution", "gtr"), ("alpha", "0.3"), ("gamma", "1"), ("lambda", "smith")], ErrorKind::InvalidValue, "\"lambda\""),
        (&[("sigma", "0.1"), ("distribution", "ggx"), ("alpha", "0.3"), ("gamma", "1")], ErrorKind::UnknownParameter, "\"gamma\""),
        (&[("sigma", "0.1"), ("distribution", "beckmann"), ("alpha", "0.3"), ("lambda", "exact")], ErrorKind::UnknownParameter, "\"lambda\""),
        (&[("sigma", "0.1"), ("alpha", "0.3"), ("stretch", "0.5")], ErrorKind::UnknownParameter, "\"stretch\""),
        (&[("sigma", "0.1"), ("distribution", "ggx"), ("alpha", "0.3"), ("stretch", "-1")], ErrorKind::InvalidValue, "\"stretch\""),
        (&[("sigma", "0.1"), ("distribution", "ggx"), ("alpha", "0.3"), ("transform_xx", "1")], ErrorKind::MissingParameter, "\"transform_yy\""),
        (&[("sigma", "0.1"), ("distribution", "ggx"), ("alpha", "0.3"), ("transform_xx", "1"), ("transform_xy", "1"), ("transform_yx", "1"),
            ("transform_yy", "1")], ErrorKind::InvalidValue, "\"transform_xx\""),
        (&[("sigma", "0.1"), ("distribution", "ggx"), ("alpha", "0.3"), ("stretch", "0.1"), ("transform_xx", "1"), ("transform_xy", "0"),
            ("transform_yx", "0"), ("transform_yy", "1")], ErrorKind::MissingParameter, "\"stretch\""),
    ];
    for (entries, kind, needle) in cases {
        let e = medium_from_params(&params(entries)).unwrap_err();
        assert_eq!(e.kind, *kind, "{entries:?}: {}", e.message);
        assert!(e.message.contains(needle), "{entries:?}: message {:?} does not name {needle}", e.message);
    }
    // A surface NDF takes no medium parameters and no gpss.
    let e = macrofacet::params::ndf_from_params(&params(&[("alpha", "0.3"), ("sigma", "1")])).unwrap_err();
    assert!(e.message.contains("\"sigma\""), "{}", e.message);
    let e = macrofacet::params::ndf_from_params(&params(&[("alpha", "0.3"), ("distribution", "gpss")])).unwrap_err();
    assert!(e.message.contains("\"distribution\""), "{}", e.message);
    let e = macrofacet::params::ndf_from_params(&params(&[("lengthscale", "0.3")])).unwrap_err();
    assert!(e.message.contains("\"lengthscale\""), "{}", e.message);
}
