// mfhost — turns the parsed Mitsuba XML tree into a renderable Scene, validating every plugin
// type, parameter name, type and value (errors name the element and its file:line).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "medium.h"
#include "scene.h"
#include "xml_scene.h"

namespace mf {

struct BuildOptions {
    /// Build everything but do not call the macrofacet hook (for --check and tests): shapes keep
    /// their parameter bags and no medium object; the scene must not be rendered then.
    bool allow_macrofacet_placeholders = false;
    /// Build and validate everything as for rendering, but accept what only the renderer cannot
    /// do yet — spatially varying medium parameters and sdfgrid mean surfaces (issue 12) — with
    /// stand-in values for the library's checks (mfrender --check): the scene must not be
    /// rendered then.
    bool validate_only = false;
    int spp_override = -1;
    long long seed_override = -1;
    int max_depth_override = -2;  // -2 = keep the scene's value
    /// Threads that build the media's mean surfaces and region boundaries (the costly part of
    /// loading a scene with mesh media), 0 = hardware concurrency. The scene does not depend on it.
    int threads = 0;
    /// Superpose macrofacet media in vacuum instead of tracing their boundaries
    /// (SceneBuilder::place_macrofacet_boundaries); false (mfrender --media-boundaries) keeps
    /// the boundaries, for comparison: both render the same image.
    bool superpose_macrofacet = true;
    /// Let a macrofacet medium whose boundary the library built, with no other geometry near it,
    /// find each ray's exit from its region itself (SceneBuilder::let_media_find_exits); false
    /// (mfrender --cast-exits) casts a ray for every exit, for comparison: the same image.
    bool media_find_exits = true;
    /// End shadow rays at the opaque cores of macrofacet shells on spheres (Scene::add_opaque_core)
    /// and play the depth roulette on shallower ones (Scene::shadow_roulette); false (mfrender
    /// --no-opaque-cores) tracks them all, for comparison: the same image, to noise.
    bool opaque_cores = true;
    /// Play the next-event rays' contribution roulette (IntegratorSettings::shadow_roulette);
    /// false (mfrender --no-shadow-roulette) traces every one, for comparison: the same image,
    /// to noise.
    bool shadow_roulette = true;
};

struct BuildReport {
    /// Every macrofacet/gpis medium reference, with the shape it is attached to.
    struct MacrofacetUse {
        std::shared_ptr<const MediumParamBag> bag;
        std::shared_ptr<const Shape> shape;
        std::string role;  // "interior" or "exterior"
    };
    std::vector<MacrofacetUse> macrofacet;
    /// What the scene asks for that mfrender leaves out without changing the image (e.g. the
    /// moment integrator's AOV channels), one line each with the element's file:line.
    std::vector<std::string> warnings;
};

/// Without `errors`, throws every problem (mf::Error or mf::ErrorList); with it, adds them there
/// and returns null if there was any (the caller reports them all at once).
std::unique_ptr<Scene> build_scene(const ParsedScene& parsed, const BuildOptions& opts, BuildReport* report,
                                   ErrorSink* errors = nullptr);

/// The plugin subset, as printed by `mfrender --help`.
const char* supported_subset_text();

}  // namespace mf
