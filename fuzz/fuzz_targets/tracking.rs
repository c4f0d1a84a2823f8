//! The tracking API: `mf_surface_new_sphere`, `_mesh`, `_grid`, `_callbacks` (valid, degenerate
//! and invalid), `mf_surface_eval`, `_bounding_box`, `_enclosure`, `mf_enclosure_*`,
//! `mf_surface_free`, `mf_track_free_flight`, `mf_track_transmittance`, their batches and
//! `mf_track_opaque_core` and `mf_track_depth_roulette` on media from the fuzz input, with callback surfaces that lie after a
//! number of calls (`fuzz/src/host.rs`) and queries biased toward the surface
//! (`fuzz/src/track.rs`).
#![no_main]

use glam::DVec3;
use libfuzzer_sys::fuzz_target;
use macrofacet_ffi::*;
use macrofacet_fuzz::build;
use macrofacet_fuzz::check;
use macrofacet_fuzz::host::Host;
use macrofacet_fuzz::input::Bytes;
use macrofacet_fuzz::surface;
use macrofacet_fuzz::track::Scene;

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    let params = build::medium_params(&mut b);
    let Some(medium) = build::medium(&params) else { return };
    let top = check::call(|o| unsafe { mf_medium_shell_top(medium.0, o) }).expect("mf_medium_shell_top");
    // The surface's size: mostly a few to 1e4 shell heights, sometimes unrelated to the shell.
    let size = if b.u8() % 8 == 0 { b.positive(-3.0, 3.0) } else { top * b.log_uniform(-1.0, 4.0) };
    let center = if b.u8() % 4 == 0 { b.sphere() * size * b.log_uniform(-2.0, 2.0) } else { DVec3::ZERO };
    let Some(built) = surface::surface(&mut b, size, center) else { return };
    let mut scene = Scene { medium: &medium, surface: &built.surface, field: None, host: Host { surface: built.host, field: None, surface_exact: built.exact }, center, size };
    scene.bounding_box();
    let mut queries = Vec::new();
    for _ in 0..1 + b.below(2) {
        let q = scene.query(&mut b);
        scene.free_flight(&q);
        scene.transmittance(&q);
        queries.push(q);
    }
    scene.batches(&queries);
    scene.opaque_core(&queries[0]);
    scene.depth_roulette(&queries[0]);
    match b.u8() % 32 {
        0 => scene.nulls(&queries[0]),
        1 => scene.enclosure(&mut b, top),
        _ => {}
    }
});
