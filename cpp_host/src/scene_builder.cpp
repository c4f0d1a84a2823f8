// mfhost — scene construction from the XML tree (see scene_builder.h).
#include "scene_builder.h"

#include <sys/stat.h>

#include <macrofacet.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <map>
#include <set>
#include <thread>

#include "image_io.h"
#include "library_abi.h"
#include "mean_surface.h"
#include "medium_gpis.h"
#include "medium_heterogeneous.h"
#include "medium_fields.h"
#include "medium_macrofacet.h"
#include "sdf_grid.h"

#include <macrofacet.h>

namespace mf {

namespace {

bool file_exists(const std::string& p) {
    struct stat st;
    return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

class Builder {
public:
    Builder(const BuildOptions& opts, BuildReport* report) : opts_(opts), report_(report) {}

    /// Builds everything it can and reports every problem to `errors` (one per object at least:
    /// an object with a problem is skipped, and objects already reported by the reader, marked
    /// broken, are skipped quietly). Returns null when there was any problem.
    std::unique_ptr<Scene> build(const ParsedScene& parsed, ErrorSink& errors) {
        scene_ = std::make_unique<Scene>();
        const SceneObject& root = *parsed.root;
        const SceneObject* sensor = nullptr;
        const SceneObject* integrator = nullptr;
        bool sensor_seen = false;
        for (const Child& c : root.children) {
            c.used = true;
            const SceneObject& o = *c.obj;
            if (o.tag == "sensor") sensor_seen = true;
            try {
                build_top_level(o, c, &sensor, &integrator);
            } catch (const AlreadyReported&) {
            } catch (const Error& e) {
                errors.add(e);
            }
        }
        finish_regions(errors);
        if (!sensor && !sensor_seen && !root.broken)
            errors.add(Error(root.loc, "the scene has no <sensor> (mfrender needs a perspective sensor)"));
        try {
            if (sensor) build_sensor(*sensor);
            if (integrator) build_integrator(*integrator);
            else scene_->integrator = IntegratorSettings{"path", false, -1, 5, false};  // Mitsuba's default: path
        } catch (const AlreadyReported&) {
        } catch (const Error& e) {
            errors.add(e);
        }
        if (!errors.empty() || !sensor) return nullptr;
        if (opts_.spp_override > 0) scene_->spp = opts_.spp_override;
        if (opts_.seed_override >= 0) scene_->seed = uint64_t(opts_.seed_override);
        if (opts_.max_depth_override >= -1) scene_->integrator.max_depth = opts_.max_depth_override;
        if (!opts_.shadow_roulette) scene_->integrator.shadow_roulette = 0.0f;
        place_macrofacet_boundaries();
        if (opts_.media_find_exits) let_media_find_exits();
        for (auto& kv : media_) scene_->media.push_back(kv.second);
        scene_->content_hash = parsed.content_hash;
        scene_->commit();
        return std::move(scene_);
    }

private:
    /// Thrown for an object whose problem the reader already reported (SceneObject::broken).
    struct AlreadyReported {};
    static void skip_if_broken(const SceneObject& o) {
        if (o.broken) throw AlreadyReported{};
    }

    void build_top_level(const SceneObject& o, const Child& c, const SceneObject** sensor, const SceneObject** integrator) {
        {
            if (o.tag == "shape") {
                build_shape(c.obj);
            } else if (o.tag == "emitter") {
                // A top-level area emitter is built by the shape that references it (Mitsuba's
                // cbox): nothing to do here.
                if (o.type != "area") scene_->add_emitter(build_emitter(o, nullptr));
            } else if (o.tag == "texture") {
                build_texture(o);
            } else if (o.tag == "volume") {
                skip_if_broken(o);  // defined for <ref>; its user checks it against its parameter
                check_volume_element(o, volume_files_);
            } else if (o.tag == "bsdf") {
                build_bsdf(o);
            } else if (o.tag == "medium") {
                build_medium(o);
            } else if (o.tag == "sensor") {
                skip_if_broken(o);
                if (*sensor) throw Error(o.loc, "only one <sensor> is supported (first at " + (*sensor)->loc.str() + ")");
                *sensor = &o;
            } else if (o.tag == "integrator") {
                skip_if_broken(o);
                if (*integrator)
                    throw Error(o.loc, "only one <integrator> is supported (first at " + (*integrator)->loc.str() + ")");
                *integrator = &o;
            } else {
                (void)c;
                throw Error(o.loc, o.describe() + " is not allowed at the top level of <scene>");
            }
        }
    }

    /// A medium whose mean surface is a shape, and the shape that bounds its region (f below
    /// the shell's top, or the gpis envelope): the mean surface (a mesh's hierarchy and grid) and
    /// the enclosure cost most of a scene's loading, so they are built after the scene graph, in
    /// parallel, then added in the order of the file.
    struct PendingRegion {
        std::shared_ptr<Shape> shape;
        std::shared_ptr<const MediumParamBag> bag;
        bool gpis;
        std::shared_ptr<const Medium> medium;
        std::shared_ptr<Shape> boundary;
        std::exception_ptr error;
    };

    /// The threads scene building may use (--threads, else one per core; at most the library's
    /// MF_MAX_BUILD_THREADS for a mesh).
    size_t build_threads() const {
        const size_t wanted = opts_.threads > 0 ? size_t(opts_.threads) : std::max(1u, std::thread::hardware_concurrency());
        return std::min<size_t>(wanted, MF_MAX_BUILD_THREADS);
    }

    void build_region(PendingRegion& r, size_t threads) {
        try {
            if (r.gpis) {
                auto surface = MeanSurface::of(*r.shape, threads);
                auto g = create_gpis_medium(*r.bag, surface);
                r.boundary = make_region_boundary(r.shape, *surface, g->envelope(), g);
                r.medium = g;
            } else {
                auto m = create_macrofacet_medium(*r.bag, *r.shape, threads);
                r.boundary = make_region_boundary(r.shape, m->surface(), m->shell_top(), m);
                r.medium = m;
            }
        } catch (...) {
            r.error = std::current_exception();
        }
    }

    void finish_regions(ErrorSink& errors) {
        // One region per thread; fewer regions than threads share the rest within each
        // (a single large mesh builds on all of them).
        const size_t total = build_threads();
        const size_t n_threads = std::min(pending_.size(), total);
        const size_t per_region = std::max<size_t>(1, total / std::max<size_t>(1, pending_.size()));
        std::atomic<size_t> next{0};
        auto work = [&] {
            for (size_t i; (i = next.fetch_add(1)) < pending_.size();) build_region(pending_[i], per_region);
        };
        std::vector<std::thread> pool;
        for (size_t t = 1; t < n_threads; ++t) pool.emplace_back(work);
        work();
        for (std::thread& t : pool) t.join();
        for (PendingRegion& r : pending_) {
            try {
                if (r.error) std::rethrow_exception(r.error);
                scene_->media.push_back(r.medium);
                if (r.gpis) {
                    has_gpis_ = true;
                    scene_->add_shape(r.boundary);
                } else {
                    macrofacet_boundaries_.push_back({r.boundary, r.medium});
                }
            } catch (const Error& e) {
                errors.add(e);
            }
        }
        pending_.clear();
    }

    const BuildOptions& opts_;
    BuildReport* report_;
    std::vector<PendingRegion> pending_;
    struct MacrofacetBoundary {
        std::shared_ptr<Shape> shape;
        std::shared_ptr<const Medium> medium;
    };
    std::vector<MacrofacetBoundary> macrofacet_boundaries_;
    bool has_gpis_ = false;
    std::unique_ptr<Scene> scene_;
    std::map<const SceneObject*, std::shared_ptr<Bsdf>> bsdfs_;
    std::map<const SceneObject*, std::shared_ptr<const Texture>> textures_;
    std::map<const SceneObject*, std::shared_ptr<const Medium>> media_;
    std::map<const SceneObject*, std::shared_ptr<const MediumParamBag>> bags_;
    /// Media and parameter bags whose build failed: reported at their first use, skipped after.
    std::set<const SceneObject*> failed_;
    /// Macrofacet media with a nested mean surface (add_boundary): the <shape> and the medium.
    std::map<const MediumParamBag*, std::shared_ptr<SceneObject>> mean_surfaces_;
    std::map<const MediumParamBag*, std::shared_ptr<const MacrofacetMedium>> boundary_media_;
    VolumeFileCache volume_files_;

    static Error err(const SceneObject& o, const std::string& msg) { return Error(o.loc, o.describe() + ": " + msg); }
    static Error perr(const SceneObject& o, const std::string& prop, const std::string& msg) {
        return Error(o.loc_of(prop), o.describe() + ": parameter \"" + prop + "\" " + msg);
    }

    std::string resolve_file(const SceneObject& o, const std::string& prop) {
        std::string path = o.resolve_path(o.get_string(prop));
        if (!file_exists(path)) throw perr(o, prop, "refers to a missing file " + quote(path, 200));
        return path;
    }

    Rgb nonneg_rgb(const SceneObject& o, const std::string& name, const Rgb& def) {
        Rgb v = o.get_rgb(name, def);
        if (!v.finite() || v.r < 0 || v.g < 0 || v.b < 0) throw perr(o, name, "must be finite and non-negative");
        return v;
    }

    // ------------------------------------------------------------------ BSDFs
    std::shared_ptr<Bsdf> build_bsdf(const SceneObject& o) {
        auto it = bsdfs_.find(&o);
        if (it != bsdfs_.end()) return it->second;
        skip_if_broken(o);
        std::shared_ptr<Bsdf> b;
        const std::string& t = o.type;
        if (t == "diffuse") {
            b = make_diffuse(texture_param(o, "reflectance", Rgb(0.5f)));
        } else if (t == "conductor" || t == "roughconductor") {
            ConductorIor ior = conductor_ior(o);
            auto spec = texture_param(o, "specular_reflectance", Rgb(1.0f));
            if (t == "conductor") {
                b = make_conductor(ior, spec);
            } else {
                std::string dist = o.get_string("distribution", "beckmann");
                if (uses_library_distribution(o, dist)) {
                    b = make_rough_conductor(ior, spec, library_distribution(o, dist));
                    o.check_all_used();
                    bsdfs_[&o] = b;
                    return b;
                }
                MicrofacetParams mp = microfacet_params(o, "\"beckmann\", \"ggx\" or \"gtr\"");
                // mfrender extension: Smith masking-shadowing form (Mitsuba: separable)
                std::string shadowing = o.get_string("shadowing", "separable");
                if (shadowing != "separable" && shadowing != "height_correlated")
                    throw perr(o, "shadowing", "must be \"separable\" or \"height_correlated\", got \"" + shadowing + "\"");
                b = make_rough_conductor(ior, spec, mp.type, mp.alpha_u, mp.alpha_v, mp.sample_visible,
                                         shadowing == "height_correlated");
            }
        } else if (t == "dielectric" || t == "thindielectric") {
            float ni = ior_value(o, "int_ior", "bk7"), ne = ior_value(o, "ext_ior", "air");
            Rgb r = nonneg_rgb(o, "specular_reflectance", Rgb(1.0f)), tr = nonneg_rgb(o, "specular_transmittance", Rgb(1.0f));
            b = t == "dielectric" ? make_dielectric(ni, ne, r, tr) : make_thin_dielectric(ni, ne, r, tr);
        } else if (t == "roughdielectric") {
            auto [ni, ne] = interface_iors(o, "bk7");
            auto r = optional_texture(o, "specular_reflectance"), tr = optional_texture(o, "specular_transmittance");
            MicrofacetParams mp = microfacet_params(o);
            b = make_rough_dielectric(ni, ne, r, tr, mp.type, mp.alpha_u, mp.alpha_v, mp.sample_visible);
        } else if (t == "plastic") {
            auto [ni, ne] = interface_iors(o, "polypropylene");
            auto diffuse = texture_param(o, "diffuse_reflectance", Rgb(0.5f));
            Rgb spec = nonneg_rgb(o, "specular_reflectance", Rgb(1.0f));
            bool nonlinear = o.get_bool("nonlinear", false);
            // Mitsuba: the specular lobe's sampling weight from the mean reflectances
            float d_mean = diffuse->mean(), s_mean = spec.average();
            b = make_plastic(ni, ne, diffuse, spec, nonlinear, s_mean + d_mean > 0 ? s_mean / (s_mean + d_mean) : 0.5f);
        } else if (t == "roughplastic") {
            auto [ni, ne] = interface_iors(o, "polypropylene");
            auto diffuse = texture_param(o, "diffuse_reflectance", Rgb(0.5f));
            auto spec = optional_texture(o, "specular_reflectance");
            bool nonlinear = o.get_bool("nonlinear", false);
            MicrofacetParams mp = microfacet_params(o);
            if (mp.alpha_u != mp.alpha_v)
                throw err(o, "roughplastic does not support anisotropic roughness (as in Mitsuba); give alpha");
            b = make_rough_plastic(ni, ne, diffuse, spec, nonlinear, mp.type, mp.alpha_u, mp.sample_visible);
        } else if (t == "null") {
            b = make_null_bsdf();
        } else if (t == "twosided") {
            auto kids = o.children_with_tag("bsdf");
            if (kids.empty() || kids.size() > 2) throw err(o, "expects one or two nested <bsdf> elements");
            std::shared_ptr<Bsdf> f = build_bsdf(*kids[0]->obj);
            std::shared_ptr<Bsdf> bk = kids.size() == 2 ? build_bsdf(*kids[1]->obj) : f;
            if (f->is_null() || bk->is_null()) throw err(o, "a null BSDF cannot be made two-sided");
            if (f->name() == "mask" || bk->name() == "mask")
                throw err(o, "a mask inside twosided is not supported: make the mask the outer BSDF (mask of twosided)");
            b = make_twosided(f, bk);
        } else if (t == "mask") {
            auto kids = o.children_with_tag("bsdf");
            if (kids.size() != 1) throw err(o, "expects one nested <bsdf>");
            std::shared_ptr<Bsdf> nested = build_bsdf(*kids[0]->obj);
            if (nested->is_null() || nested->name() == "mask") throw err(o, "the nested BSDF of a mask cannot be null or a mask");
            b = make_mask(texture_param(o, "opacity", Rgb(0.5f)), nested);
        } else if (t == "normalmap") {
            auto kids = o.children_with_tag("bsdf");
            if (kids.size() != 1) throw err(o, "expects one nested <bsdf>");
            std::shared_ptr<Bsdf> nested = build_bsdf(*kids[0]->obj);
            if (nested->is_null() || nested->name() == "mask") throw err(o, "the nested BSDF of a normalmap cannot be null or a mask");
            if (!o.child_named("texture", "normalmap") && !o.has("normalmap")) throw err(o, "needs a \"normalmap\" texture");
            b = make_normal_map(texture_param(o, "normalmap", Rgb(0.5f, 0.5f, 1.0f)), nested, o.get_bool("use_shadowing_function", true));
        } else {
            throw err(o, "unsupported BSDF plugin \"" + t +
                             "\" (supported: diffuse, conductor, roughconductor, dielectric, thindielectric, roughdielectric, plastic, roughplastic, null, twosided, mask, normalmap)");
        }
        o.check_all_used();
        bsdfs_[&o] = b;
        return b;
    }

    // ------------------------------------------------------------------ textures
    /// A parameter Mitsuba takes as a texture: a constant property (<rgb>, <float>, <spectrum>),
    /// a nested <texture name="..."> or a <ref name="..." id="..."/> to a texture.
    std::shared_ptr<const Texture> texture_param(const SceneObject& o, const std::string& name, const Rgb& def) {
        const Child* c = o.child_named("texture", name);
        if (c && o.has(name)) throw err(o, "parameter " + quote(name) + " is given twice (a value and a texture)");
        if (c) return build_texture(*c->obj);
        return make_constant_texture(nonneg_rgb(o, name, def));
    }

    std::shared_ptr<const Texture> build_texture(const SceneObject& t) {
        auto it = textures_.find(&t);
        if (it != textures_.end()) return it->second;
        skip_if_broken(t);
        UvTransform to_uv = UvTransform::from(t.get_transform("to_uv", Mat4()));
        std::shared_ptr<const Texture> tex;
        if (t.type == "checkerboard") {
            auto c0 = texture_param(t, "color0", Rgb(0.4f)), c1 = texture_param(t, "color1", Rgb(0.2f));
            tex = make_checkerboard_texture(std::const_pointer_cast<Texture>(c0), std::const_pointer_cast<Texture>(c1), to_uv);
        } else if (t.type == "bitmap") {
            std::string path = resolve_file(t, "filename");
            std::string ft = t.get_string("filter_type", "bilinear"), wm = t.get_string("wrap_mode", "repeat");
            BitmapFilter f;
            if (ft == "bilinear") f = BitmapFilter::Bilinear;
            else if (ft == "nearest") f = BitmapFilter::Nearest;
            else throw perr(t, "filter_type", "must be bilinear or nearest, got " + quote(ft));
            WrapMode w;
            if (wm == "repeat") w = WrapMode::Repeat;
            else if (wm == "mirror") w = WrapMode::Mirror;
            else if (wm == "clamp") w = WrapMode::Clamp;
            else throw perr(t, "wrap_mode", "must be repeat, mirror or clamp, got " + quote(wm));
            bool raw = t.get_bool("raw", false);
            std::string format = t.get_string("format", "variant");
            if (format != "variant" && format != "fp32" && format != "fp16")
                throw perr(t, "format", "must be variant, fp16 or fp32, got " + quote(format));
            Image img;
            try {
                img = read_texture_image(path, raw);
            } catch (const Error& e) {
                throw Error(t.loc, t.describe() + ": " + e.what());
            }
            for (float v : img.rgb)
                if (!(v >= 0) || !std::isfinite(v)) throw err(t, "image " + quote(path, 200) + " has negative or non-finite values");
            tex = make_bitmap_texture(std::move(img.rgb), img.width, img.height, f, w, to_uv);
        } else if (t.type == "mesh_attribute") {
            std::string name = t.get_string("name");
            if (name != "vertex_color" && name != "face_color")
                throw perr(t, "name", "must be vertex_color or face_color (the attributes mfrender reads from PLY r, g, b), got " + quote(name));
            tex = make_mesh_attribute_texture(name, t.get_float("scale", 1.0f));
        } else {
            throw err(t, "unsupported texture plugin " + quote(t.type) + " (supported: bitmap, checkerboard, mesh_attribute)");
        }
        t.check_all_used();
        textures_[&t] = tex;
        return tex;
    }

    /// The roughconductor parameters the library's distributions take beyond mfrender's own.
    static const std::vector<std::string>& library_float_params() {
        static const std::vector<std::string> names = {"gamma", "stretch", "transform_xx", "transform_xy",
                                                       "transform_yx", "transform_yy"};
        return names;
    }

    /// GTR and the microsurface transforms (seeds/001) are the library's (mf_ndf).
    static bool uses_library_distribution(const SceneObject& o, const std::string& dist) {
        if (dist == "gtr" || o.has("lambda")) return true;
        for (const auto& n : library_float_params())
            if (o.has(n)) return true;
        return false;
    }

    /// Fills an mf_params from the roughconductor's distribution parameters and builds the
    /// library distribution; a library error is reported at the parameter it names.
    std::shared_ptr<const LibraryMicrofacet> library_distribution(const SceneObject& o, const std::string& dist) {
        if (!o.get_bool("sample_visible", true))
            throw perr(o, "sample_visible", "must be true for distribution " + quote(dist) + " and microsurface transforms (the library samples visible normals exactly)");
        std::string shadowing = o.get_string("shadowing", "separable");
        if (shadowing != "separable" && shadowing != "height_correlated")
            throw perr(o, "shadowing", "must be \"separable\" or \"height_correlated\", got \"" + shadowing + "\"");
        mf_params* params = nullptr;
        if (mf_params_new(&params) != MF_OK) throw err(o, "mf_params_new failed");
        std::unique_ptr<mf_params, void (*)(mf_params*)> guard(params, mf_params_free);
        std::vector<std::string> names = {"alpha", "alpha_u", "alpha_v"};
        names.insert(names.end(), library_float_params().begin(), library_float_params().end());
        bool ok = mf_params_set_string(params, "distribution", dist.c_str()) == MF_OK;
        for (const auto& n : names)
            if (o.has(n)) ok = ok && mf_params_set_float(params, n.c_str(), o.get_float(n)) == MF_OK;
        if (o.has("lambda")) ok = ok && mf_params_set_string(params, "lambda", o.get_string("lambda").c_str()) == MF_OK;
        if (!o.has("alpha") && !o.has("alpha_u") && !o.has("alpha_v"))  // Mitsuba's default roughness
            ok = ok && mf_params_set_float(params, "alpha", 0.1) == MF_OK;
        try {
            if (!ok) throw Error(mf_last_error());
            return make_library_microfacet(params, shadowing == "height_correlated", "roughconductor");
        } catch (const Error& e) {
            std::string msg = e.what();
            names.insert(names.end(), {"distribution", "lambda"});
            for (const auto& n : names)
                if (o.has(n) && msg.find("\"" + n + "\"") != std::string::npos) throw perr(o, n, msg);
            throw err(o, msg);
        }
    }

    /// Mitsuba's MicrofacetDistribution(props): distribution beckmann (default) | ggx, alpha
    /// (default 0.1) or alpha_u and alpha_v, sample_visible (default true).
    struct MicrofacetParams {
        MicrofacetType type = MicrofacetType::Beckmann;
        float alpha_u = 0.1f, alpha_v = 0.1f;
        bool sample_visible = true;
    };
    /// `choices` names every distribution the caller accepts (roughconductor also takes the
    /// library's, handled before).
    MicrofacetParams microfacet_params(const SceneObject& o, const std::string& choices = "\"beckmann\" or \"ggx\"") {
        MicrofacetParams mp;
        std::string dist = o.get_string("distribution", "beckmann");
        if (dist == "beckmann") mp.type = MicrofacetType::Beckmann;
        else if (dist == "ggx") mp.type = MicrofacetType::GGX;
        else throw perr(o, "distribution", "must be " + choices + ", got \"" + dist + "\"");
        if (o.has("alpha_u") || o.has("alpha_v")) {
            if (o.has("alpha")) throw err(o, "specify either alpha or alpha_u/alpha_v, not both");
            if (!o.has("alpha_u") || !o.has("alpha_v")) throw err(o, "alpha_u and alpha_v must both be given");
            mp.alpha_u = roughness(o, "alpha_u");
            mp.alpha_v = roughness(o, "alpha_v");
        } else if (o.has("alpha")) {
            mp.alpha_u = mp.alpha_v = roughness(o, "alpha");
        }
        mp.sample_visible = o.get_bool("sample_visible", true);
        return mp;
    }

    /// int_ior / ext_ior of a dielectric interface (Mitsuba: both positive and different).
    std::pair<float, float> interface_iors(const SceneObject& o, const std::string& int_default) {
        float ni = ior_value(o, "int_ior", int_default), ne = ior_value(o, "ext_ior", "air");
        if (ni == ne) throw err(o, "int_ior and ext_ior must differ (Mitsuba refuses an interface that does not refract)");
        return {ni, ne};
    }

    /// An optional texture parameter (null when absent: Mitsuba's "no factor").
    std::shared_ptr<const Texture> optional_texture(const SceneObject& o, const std::string& name) {
        if (!o.has(name) && !o.child_named("texture", name)) return nullptr;
        return texture_param(o, name, Rgb(1.0f));
    }

    float roughness(const SceneObject& o, const std::string& name) {
        float a = o.get_float(name);
        if (!(a >= 0)) throw perr(o, name, "must be a non-negative roughness, got " + std::to_string(a));
        return a;
    }

    ConductorIor conductor_ior(const SceneObject& o) {
        ConductorIor ior;
        if (o.has("eta") || o.has("k")) {
            if (o.has("material")) throw err(o, "specify either material or eta/k, not both");
            ior.eta = o.get_rgb("eta", Rgb(0.0f));
            ior.k = o.get_rgb("k", Rgb(1.0f));
            if (!ior.eta.finite() || !ior.k.finite() || ior.eta.r < 0 || ior.eta.g < 0 || ior.eta.b < 0 || ior.k.r < 0 ||
                ior.k.g < 0 || ior.k.b < 0)
                throw err(o, "eta and k must be finite and non-negative");
            ior.perfect = false;
            return ior;
        }
        std::string mat = o.get_string("material", "none");
        if (!conductor_preset(mat, &ior))
            throw perr(o, "material", "names an unknown conductor \"" + mat + "\" (supported: " + conductor_preset_list() + ")");
        return ior;
    }

    float ior_value(const SceneObject& o, const std::string& name, const std::string& def) {
        const Property* p = o.find(name);
        float v;
        if (!p) {
            dielectric_ior_by_name(def, &v);
            return v;
        }
        if (p->type == PropType::String) {
            if (!dielectric_ior_by_name(p->s, &v))
                throw perr(o, name, "names an unknown material \"" + p->s + "\" (e.g. vacuum, air, water, bk7, diamond)");
            return v;
        }
        v = o.get_float(name, 1.0f);
        if (!(v > 0)) throw perr(o, name, "must be a positive index of refraction");
        return v;
    }

    // ------------------------------------------------------------------ media
    std::shared_ptr<PhaseFunction> build_phase(const SceneObject& o) {
        skip_if_broken(o);
        std::shared_ptr<PhaseFunction> ph;
        if (o.type == "isotropic") {
            ph = std::make_shared<IsotropicPhase>();
        } else if (o.type == "hg") {
            float g = o.get_float("g", 0.8f);
            if (!(g > -1 && g < 1)) throw perr(o, "g", "must lie in (-1, 1)");
            ph = std::make_shared<HenyeyGreenstein>(g);
        } else {
            throw err(o, "unsupported phase function \"" + o.type + "\" (supported: isotropic, hg)");
        }
        o.check_all_used();
        return ph;
    }

    static bool is_macrofacet(const SceneObject& o) { return o.type == "macrofacet" || o.type == "gpis"; }

    std::shared_ptr<const MediumParamBag> build_bag(const SceneObject& o) {
        auto it = bags_.find(&o);
        if (it != bags_.end()) return it->second;
        skip_if_broken(o);
        if (failed_.count(&o)) throw AlreadyReported{};  // reported at its first use
        try {
            return build_bag_once(o);
        } catch (const Error&) {
            failed_.insert(&o);
            throw;
        }
    }

    std::shared_ptr<const MediumParamBag> build_bag_once(const SceneObject& o) {
        auto bag = std::make_shared<MediumParamBag>();
        bag->type = o.type;
        bag->id = o.id;
        bag->loc = o.loc;
        for (const Property& p : o.props) {
            p.used = true;
            ParamValue v;
            v.loc = p.loc;
            switch (p.type) {
                case PropType::Float:
                    v.kind = ParamValue::Kind::Float;
                    v.f = p.f;
                    break;
                case PropType::Integer:
                    v.kind = ParamValue::Kind::Int;
                    v.i = p.i;
                    break;
                case PropType::Boolean:
                    v.kind = ParamValue::Kind::Bool;
                    v.b = p.b;
                    break;
                case PropType::String:
                    v.kind = ParamValue::Kind::String;
                    v.s = p.s;
                    break;
                case PropType::Rgb:
                    v.kind = ParamValue::Kind::Rgb;
                    v.rgb = p.rgb;
                    break;
                default:
                    throw Error(p.loc, o.describe() + ": parameter \"" + p.name + "\" has type " + prop_type_name(p.type) +
                                           ", which a macrofacet parameter bag cannot hold (float, rgb, string, "
                                           "integer or boolean)");
            }
            bag->params.emplace_back(p.name, v);
        }
        if (const Child* ms = o.child_named("shape", "mean_surface")) {
            if (o.type != "macrofacet") throw Error(ms->loc, o.describe() + ": only a macrofacet medium takes a nested mean surface");
            mean_surfaces_[bag.get()] = ms->obj;
        }
        // Spatially varying parameters (nested or referenced volumes and textures; issue 12).
        bag->fields = build_medium_fields(o, bag.get(), volume_files_, [this](const SceneObject& t) { return build_texture(t); });
        o.check_all_used();  // other nested objects are not allowed in the bag
        bags_[&o] = bag;
        return bag;
    }

    std::shared_ptr<const Medium> build_medium(const SceneObject& o) {
        if (is_macrofacet(o)) {
            build_bag(o);
            return nullptr;
        }
        auto it = media_.find(&o);
        if (it != media_.end()) return it->second;
        skip_if_broken(o);
        if (failed_.count(&o)) throw AlreadyReported{};  // reported at its first use
        try {
            auto m = build_medium_once(o);
            media_[&o] = m;
            return m;
        } catch (const Error&) {
            failed_.insert(&o);
            throw;
        }
    }

    /// A homogeneous or heterogeneous medium (build_medium caches it, or its failure).
    std::shared_ptr<const Medium> build_medium_once(const SceneObject& o) {
        if (o.type == "heterogeneous") return build_heterogeneous(o);
        if (o.type != "homogeneous")
            throw err(o, "unsupported medium plugin \"" + o.type + "\" (supported: homogeneous, heterogeneous, macrofacet, gpis)");
        Rgb sigma_t = nonneg_rgb(o, "sigma_t", Rgb(1.0f));
        Rgb albedo = nonneg_rgb(o, "albedo", Rgb(0.75f));
        if (albedo.max() > 1.0f) throw perr(o, "albedo", "must lie in [0, 1]");
        float scale = o.get_float("scale", 1.0f);
        if (!(scale >= 0)) throw perr(o, "scale", "must be non-negative");
        o.get_bool("sample_emitters", true);  // accepted; next-event estimation is always used
        std::shared_ptr<PhaseFunction> ph = medium_phase(o);
        o.check_all_used();
        return std::make_shared<HomogeneousMedium>(sigma_t * scale, albedo, ph);
    }

    /// The nested <phase> of a medium (isotropic without one).
    std::shared_ptr<PhaseFunction> medium_phase(const SceneObject& o) {
        auto phases = o.children_with_tag("phase");
        if (phases.size() > 1) throw err(o, "expects at most one nested <phase>");
        return phases.empty() ? std::make_shared<IsotropicPhase>() : build_phase(*phases[0]->obj);
    }

    /// A volume parameter of a medium as Mitsuba's props.volume() reads it: a nested or referenced
    /// <volume>, or a constant (a constvolume with its default box, the unit cube).
    std::shared_ptr<const Volume> medium_volume(const SceneObject& o, const std::string& name, float def, float max_value,
                                                Aabb* box) {
        const Child* c = o.child_named("volume", name);
        if (c && o.has(name)) throw err(o, "parameter " + quote(name) + " is given twice (a value and a volume)");
        if (c) {
            skip_if_broken(*c->obj);
            return build_rgb_volume(*c->obj, volume_files_, max_value, box);
        }
        Rgb v = nonneg_rgb(o, name, Rgb(def));
        if (v.max() > max_value) throw perr(o, name, "must lie in [0, " + number_str(max_value) + "]");
        *box = Aabb();
        box->expand(Vec3(0.0f));
        box->expand(Vec3(1.0f));
        const float value[3] = {v.r, v.g, v.b};
        return make_constant_volume(value, 3, 3);
    }

    std::shared_ptr<const Medium> build_heterogeneous(const SceneObject& o) {
        Aabb box, albedo_box;
        auto sigma_t = medium_volume(o, "sigma_t", 1.0f, kInf, &box);
        auto albedo = medium_volume(o, "albedo", 0.75f, 1.0f, &albedo_box);
        float scale = o.get_float("scale", 1.0f);
        if (!(scale >= 0 && std::isfinite(scale))) throw perr(o, "scale", "must be finite and non-negative");
        o.get_bool("sample_emitters", true);  // accepted; next-event estimation is always used
        if (!o.get_bool("has_spectral_extinction", true))
            throw perr(o, "has_spectral_extinction", "false is not supported (mfrender tracks RGB extinction)");
        std::shared_ptr<PhaseFunction> ph = medium_phase(o);
        o.check_all_used();
        return std::make_shared<HeterogeneousMedium>(sigma_t, scale, albedo, box, ph);
    }

    // ------------------------------------------------------------------ shapes
    /// The geometry of a <shape> (its type's parameters, to_world, flip_normals); the caller
    /// adds BSDF, media and emitter.
    std::shared_ptr<Shape> build_geometry(const SceneObject& o, const Mat4& instance_to_world = Mat4()) {
        const std::string& t = o.type;
        Mat4 to_world = instance_to_world * o.get_transform("to_world", Mat4());
        if (std::fabs(to_world.det3()) < 1e-30) throw perr(o, "to_world", "is singular");
        bool flip = o.get_bool("flip_normals", false);
        std::shared_ptr<Shape> shape;
        if (t == "obj" || t == "ply" || t == "serialized") {
            std::string path = resolve_file(o, "filename");
            bool face_normals = o.get_bool("face_normals", false);
            long long shape_index = t == "serialized" ? o.get_int("shape_index", 0) : 0;
            if (shape_index < 0 || shape_index > (1 << 30)) throw perr(o, "shape_index", "must be >= 0");
            bool flip_tc = t == "obj" && o.get_bool("flip_tex_coords", true);
            TriMesh m;
            try {
                bool file_face_normals = false;
                if (t == "serialized") m = load_serialized(path, int(shape_index), &file_face_normals);
                else m = t == "obj" ? load_obj(path) : load_ply(path);
                face_normals = face_normals || file_face_normals;
            } catch (const Error& e) {
                throw Error(o.loc, o.describe() + ": " + e.what());
            }
            if (flip_tc)  // Mitsuba's OBJ loader: v -> 1 - v unless flip_tex_coords is false
                for (Vec2& q : m.uv) q.y = 1.0f - q.y;
            if (face_normals) m.make_face_normals();
            m.transform(to_world);
            if (!face_normals && m.n.empty()) m.compute_vertex_normals();
            if (flip) m.flip_normals();
            shape = std::make_shared<MeshShape>(std::move(m), t, flip);
        } else if (t == "sphere") {
            Vec3 c = o.get_point("center", Vec3(0.0f));
            float r = o.get_float("radius", 1.0f);
            if (!(r > 0)) throw perr(o, "radius", "must be positive");
            double s = to_world.similarity_scale(1e-4);
            if (s < 0) throw perr(o, "to_world", "of a sphere must be a similarity (rotation, uniform scale, translation)");
            Mat4 rot = to_world * Mat4::scale(1.0 / s, 1.0 / s, 1.0 / s);  // object frame for uv, dp/du
            rot.m[0][3] = rot.m[1][3] = rot.m[2][3] = 0.0;
            shape = std::make_shared<SphereShape>(to_world.point(c), float(r * s), flip, rot);
        } else if (t == "rectangle" || t == "cube" || t == "disk") {
            TriMesh m = t == "rectangle" ? make_rectangle_mesh() : (t == "cube" ? make_cube_mesh() : make_disk_mesh());
            m.transform(to_world);
            if (flip) m.flip_normals();
            auto ms = std::make_shared<MeshShape>(std::move(m), t, flip);
            if (t == "disk") {
                // Mitsuba's disk: uv = (r, phi / 2 pi), dp/du = to_world * (cos phi, sin phi, 0)
                Mat4 inv = to_world.inverse();
                ms->set_parameterization([=](const Vec3& p, Vec2* uv, Vec3* dpdu) {
                    Vec3 l = inv.point(p);
                    float r = std::sqrt(l.x * l.x + l.y * l.y);
                    float v = std::atan2(l.y, l.x) * (0.5f * kInvPi);
                    if (v < 0) v += 1.0f;
                    *uv = Vec2(r, v);
                    *dpdu = to_world.vector(r > 0 ? Vec3(l.x / r, l.y / r, 0.0f) : Vec3(1, 0, 0));
                });
            }
            shape = ms;
        } else if (t == "cylinder") {
            // Mitsuba's cylinder: to_world * translate(p0) * frame(p1 - p0) * scale(r, r, |p1 - p0|)
            // around the canonical one (radius 1, z in [0, 1], no caps)
            Vec3 p0 = o.get_point("p0", Vec3(0, 0, 0)), p1 = o.get_point("p1", Vec3(0, 0, 1));
            float r = o.get_float("radius", 1.0f), len = length(p1 - p0);
            if (!(r > 0) || !std::isfinite(r)) throw perr(o, "radius", "must be positive");
            if (!(len > 0) || !std::isfinite(len)) throw err(o, "p0 and p1 must be distinct finite points");
            Frame axis(normalize(p1 - p0));
            Mat4 frame;
            for (int row = 0; row < 3; ++row) {
                frame.m[row][0] = axis.s[row];
                frame.m[row][1] = axis.t[row];
                frame.m[row][2] = axis.n[row];
            }
            Mat4 local = to_world * Mat4::translate(p0.x, p0.y, p0.z) * frame * Mat4::scale(r, r, len);
            TriMesh m = make_cylinder_mesh();
            m.transform(local);
            if (flip) m.flip_normals();
            auto ms = std::make_shared<MeshShape>(std::move(m), t, flip);
            // uv = (phi / 2 pi, z) and dp/du = local * (-y, x, 0) * 2 pi at the canonical point (x, y, z)
            Mat4 inv = local.inverse();
            ms->set_parameterization([=](const Vec3& p, Vec2* uv, Vec3* dpdu) {
                Vec3 l = inv.point(p);
                float u = std::atan2(l.y, l.x) * (0.5f * kInvPi);
                if (u < 0) u += 1.0f;
                *uv = Vec2(u, l.z);
                float rl = std::sqrt(l.x * l.x + l.y * l.y);
                Vec3 tangent = rl > 0 ? Vec3(-l.y / rl, l.x / rl, 0.0f) : Vec3(0, 1, 0);
                *dpdu = local.vector(tangent * (2.0f * kPi));
            });
            shape = ms;
        } else if (t == "sdfgrid") {
            if (flip) throw perr(o, "flip_normals", "is not supported by an sdfgrid mean surface (negate its values instead)");
            shape = std::make_shared<SdfGridShape>(load_sdf_grid(o, to_world));
        } else {
            throw err(o, "unsupported shape plugin \"" + t +
                             "\" (supported: obj, ply, serialized, sphere, rectangle, cube, disk, cylinder, sdfgrid, "
                             "shapegroup, instance)");
        }
        shape->id = o.id;
        shape->loc = o.loc;
        return shape;
    }

    /// Every mesh_attribute texture of the shape's BSDF must find its attribute on the shape
    /// (Mitsuba refuses the render otherwise: "Invalid attribute requested").
    void check_mesh_attributes(const SceneObject& o, const Shape& shape) {
        std::vector<const SceneObject*> todo;
        for (const Child* c : o.children_with_tag("bsdf")) todo.push_back(c->obj.get());
        for (size_t k = 0; k < todo.size() && k < 4096; ++k) {  // the reader bounds nesting; 4096 bounds shared refs
            const SceneObject& x = *todo[k];
            if (x.tag == "texture" && x.type == "mesh_attribute" && x.has("name")) {
                auto* mesh = dynamic_cast<const MeshShape*>(&shape);
                std::string name = x.get_string("name");
                if (!mesh || !mesh->mesh().attribute(name))
                    throw err(o, "has no mesh attribute " + quote(name) + " for the mesh_attribute texture of its BSDF (" +
                                     x.loc.str() + "; PLY files give vertex_color / face_color from r, g, b properties)");
            }
            for (const Child& c : x.children) todo.push_back(c.obj.get());
        }
    }

    /// Mitsuba's shapegroup: shapes that are rendered only through instances; checked here.
    void check_shapegroup(const SceneObject& group) {
        skip_if_broken(group);
        for (const Child* c : group.children_with_tag("emitter"))
            throw Error(c->loc, group.describe() + ": emitters cannot be instanced (as in Mitsuba)");
        for (const Child* c : group.children_with_tag("shape")) {
            const SceneObject& member = *c->obj;
            if (member.type == "shapegroup" || member.type == "instance")
                throw Error(c->loc, group.describe() + ": nested instancing is not supported (as in Mitsuba)");
            if (member.type == "sdfgrid" || !member.children_with_tag("emitter").empty() ||
                !member.children_with_tag("medium").empty())
                throw Error(c->loc, group.describe() + ": " + member.describe() +
                                        " cannot be instanced (emitters, media and sdfgrid mean surfaces are refused)");
        }
        group.check_all_used();
    }

    /// Mitsuba's instance: the shapes of one referenced shapegroup, placed by the instance's
    /// to_world. mfrender builds each member as its own shape with to_world = instance * member
    /// (the same surfaces, uv and dp/du as Mitsuba's instanced BVH; memory grows per instance).
    void build_instance(const SceneObject& o) {
        skip_if_broken(o);
        auto groups = o.children_with_tag("shape");
        if (groups.size() != 1 || groups[0]->obj->type != "shapegroup")
            throw err(o, "expects exactly one <ref> to a <shape type=\"shapegroup\">");
        const SceneObject& group = *groups[0]->obj;
        check_shapegroup(group);
        Mat4 to_world = o.get_transform("to_world", Mat4());
        if (std::fabs(to_world.det3()) < 1e-30) throw perr(o, "to_world", "is singular");
        o.check_all_used();
        for (const Child* c : group.children_with_tag("shape")) build_shape(c->obj, to_world);
    }

    void build_shape(const std::shared_ptr<SceneObject>& op, const Mat4& instance_to_world = Mat4()) {
        const SceneObject& o = *op;
        skip_if_broken(o);
        const std::string& t = o.type;
        if (t == "shapegroup") return check_shapegroup(o);
        if (t == "instance") return build_instance(o);
        std::shared_ptr<Shape> shape = build_geometry(o, instance_to_world);
        check_mesh_attributes(o, *shape);

        auto bsdfs = o.children_with_tag("bsdf");
        if (bsdfs.size() > 1) throw err(o, "has more than one BSDF");
        auto ems = o.children_with_tag("emitter");
        // No <bsdf>: Mitsuba 3's default (Shape's constructor) is diffuse 0.5, but black for an
        // area emitter, which then reflects nothing.
        shape->bsdf = bsdfs.empty() ? make_diffuse(Rgb(ems.empty() ? 0.5f : 0.0f)) : build_bsdf(*bsdfs[0]->obj);

        std::shared_ptr<const MediumParamBag> mf_bag[2];
        for (const Child* c : o.children_with_tag("medium")) {
            if (c->name != "interior" && c->name != "exterior")
                throw Error(c->loc, o.describe() + ": a medium inside a shape needs name=\"interior\" or name=\"exterior\"");
            bool interior = c->name == "interior";
            if ((interior && (shape->interior || shape->interior_bag)) || (!interior && (shape->exterior || shape->exterior_bag)))
                throw Error(c->loc, o.describe() + ": more than one " + c->name + " medium");
            if (is_macrofacet(*c->obj)) {
                auto bag = build_bag(*c->obj);
                (interior ? shape->interior_bag : shape->exterior_bag) = bag;
                mf_bag[interior ? 0 : 1] = bag;
            } else {
                (interior ? shape->interior : shape->exterior) = build_medium(*c->obj);
            }
        }
        if (ems.size() > 1) throw err(o, "has more than one emitter");
        std::shared_ptr<Emitter> em;
        if (!ems.empty()) {
            const SceneObject& eo = *ems[0]->obj;
            if (eo.type != "area") throw Error(eo.loc, eo.describe() + ": only area emitters can be attached to a shape");
            em = build_emitter(eo, shape.get());
            shape->emitter = em.get();
        }
        o.check_all_used();
        if (t == "sdfgrid" && !mf_bag[0])
            throw err(o, "sdfgrid is supported as the mean surface of a macrofacet medium (a <medium type=\"macrofacet\"> or "
                         "\"gpis\" named \"interior\")");
        if (mf_bag[0]) check_mean_surface_fields(*mf_bag[0], *shape);

        for (int k = 0; k < 2; ++k) {
            if (!mf_bag[k]) continue;
            const char* role = k == 0 ? "interior" : "exterior";
            if (report_) report_->macrofacet.push_back({mf_bag[k], shape, role});
        }
        if (mf_bag[0] && mean_surfaces_.count(mf_bag[0].get()) && !opts_.allow_macrofacet_placeholders) {
            if (mf_bag[1]) throw Error(mf_bag[1]->loc, o.describe() + ": a macrofacet medium must be the interior of its boundary");
            if (bsdfs.empty() || !shape->bsdf->is_null())
                throw err(o, "the boundary of a macrofacet medium needs <bsdf type=\"null\"/> (Mitsuba gives a shape without "
                             "a BSDF a diffuse one)");
            if (em) throw Error(ems[0]->loc, o.describe() + ": the boundary of a macrofacet medium cannot be an emitter");
            add_boundary(o, shape, mf_bag[0]);
            return;
        }
        if ((mf_bag[0] || mf_bag[1]) && !opts_.allow_macrofacet_placeholders) {
            // The shape is the mean surface of a macrofacet (or gpis) medium: the medium
            // fills f < top (k*sigma, resp. the gpis envelope), and the boundary f = top replaces
            // the shape in the BVH (make_region_boundary: one mechanism for both).
            const std::string kind = (mf_bag[0] ? mf_bag[0] : mf_bag[1])->type;
            if (mf_bag[1])
                throw Error(mf_bag[1]->loc, o.describe() + ": a " + kind + " medium must be the interior of its shape "
                                                           "(the shape is its mean surface)");
            if (!bsdfs.empty() && !shape->bsdf->is_null())
                throw Error(bsdfs[0]->loc, o.describe() + ": the mean surface of a " + kind + " medium has no BSDF of "
                                                          "its own (the medium replaces it): use <bsdf type=\"null\"/> or none");
            if (em) throw Error(ems[0]->loc, o.describe() + ": the mean surface of a " + kind + " medium cannot be an emitter");
            shape->bsdf = make_null_bsdf();  // (shape->interior stays empty: the medium owns the shape)
            // Built by finish_regions, in parallel with the other media's.
            pending_.push_back(PendingRegion{shape, mf_bag[0], kind == "gpis", nullptr, nullptr, nullptr});
            return;
        }
        if (t == "sdfgrid") return;  // (placeholders: the medium is not built, nothing to trace)
        scene_->add_shape(shape);
        if (em) scene_->add_emitter(em);
    }

    // ------------------------------------------------------------------ macrofacet boundaries
    // The form that Mitsuba 3 with the macrofacet plugin reads too (mitsuba_plugin/): the medium
    // nests its mean surface as <shape name="mean_surface">, and a shape whose interior is the
    // medium is the boundary through which rays enter it, as in Mitsuba. The boundary must have a
    // null BSDF and contain the region f < k sigma; mfrender uses it as the medium's Embree
    // boundary (instead of make_region_boundary), so both renderers see the same geometry.

    void add_boundary(const SceneObject& o, const std::shared_ptr<Shape>& boundary, const std::shared_ptr<const MediumParamBag>& bag) {
        auto it = boundary_media_.find(bag.get());
        if (it == boundary_media_.end()) {
            const SceneObject& ms = *mean_surfaces_.at(bag.get());
            skip_if_broken(ms);
            std::shared_ptr<Shape> mean = build_geometry(ms);
            if (ms.type != "sphere" && ms.get_bool("flip_normals", false))  // as the plugin
                throw perr(ms, "flip_normals", "is not allowed on a mesh mean surface (its triangles' winding defines the interior)");
            ms.check_all_used();  // the mean surface is geometry only
            auto m = create_macrofacet_medium(*bag, *mean, build_threads());
            scene_->media.push_back(m);
            it = boundary_media_.emplace(bag.get(), m).first;
        }
        check_boundary(o, *boundary, *it->second);
        boundary->interior = it->second;
        macrofacet_boundaries_.push_back({boundary, it->second});
    }

    /// Macrofacet media go into the BVH behind their boundaries or, when every one of them sits
    /// in vacuum and the scene has no other medium, those bounded by a sphere are superposed
    /// (SuperposedMedium): the same image without two boundary crossings per pass through a shell.
    /// Their extinction vanishes above the shell's top, which the boundary contains
    /// (make_region_boundary, check_boundary), so tracking each ray over its chord of the
    /// boundary adds nothing. Another medium (a fog around a shell, a gpis medium, the camera's)
    /// keeps the boundaries, whose crossings switch between media as in Mitsuba. Mesh boundaries
    /// stay: their BVH finds where a ray meets the region faster than the library's bounding box.
    void place_macrofacet_boundaries() {
        bool superpose = opts_.superpose_macrofacet && media_.empty() && !has_gpis_;
        for (const auto& b : macrofacet_boundaries_) superpose = superpose && !b.shape->exterior && !b.shape->exterior_bag;
        std::map<const Medium*, int> boundaries_of;
        for (const auto& b : macrofacet_boundaries_) ++boundaries_of[b.medium.get()];
        // A sphere's shell has its opaque core, however its region is placed.
        for (const auto& entry : boundaries_of) {
            auto* m = dynamic_cast<const MacrofacetMedium*>(entry.first);
            double start, core;
            if (!opts_.opaque_cores || !m) continue;
            if (const MeanSurface::Sphere* s = m->sphere_core(&start, &core)) scene_->add_opaque_core(s->center, s->radius, start, core, m);
        }
        for (const auto& b : macrofacet_boundaries_) {
            // (a medium with several boundaries, as Mitsuba allows, keeps them: its region is their union)
            auto sphere = std::dynamic_pointer_cast<const SphereShape>(b.shape);
            if (superpose && sphere && !sphere->flipped() && boundaries_of[b.medium.get()] == 1)
                scene_->add_superposed_medium(SuperposedMedium(b.medium.get(), sphere));
            else
                scene_->add_shape(b.shape);
        }
        macrofacet_boundaries_.clear();
    }

    /// A macrofacet medium whose region boundary is the library's enclosure of a mesh (its exit
    /// level known; spheres' boundaries have none yet, and in vacuum they are superposed)
    /// finds each ray's exit itself (mf_track_query::exit_level) when no medium transition lies
    /// in the boundary's box grown by that level: a ray inside is then cast against the shapes
    /// in that box only (Scene::add_near_scene), without the boundary, instead of against the
    /// scene for the boundary's exit and again beyond it. The tracker may follow a ray anywhere
    /// in that box until it finds it outside the region; the shapes there bound its flights.
    void let_media_find_exits() {
        const std::vector<std::shared_ptr<Shape>> shapes = scene_->shapes();
        for (const auto& s : shapes) {
            auto medium = std::dynamic_pointer_cast<const MacrofacetMedium>(s->interior);
            // (an exit level comes with a library enclosure, which only a bounded surface has)
            if (!s->region_boundary || !(s->exit_level > 0) || !medium) continue;
            Aabb box = s->bounds();
            const float grow = float(s->exit_level) + 1e-4f * std::max({box.extent().x, box.extent().y, box.extent().z});
            box.lo = box.lo - Vec3(grow);
            box.hi = box.hi + Vec3(grow);
            std::vector<std::shared_ptr<Shape>> near;
            bool eligible = true;
            for (const auto& other : shapes) {
                if (other == s) continue;
                const Aabb b = other->bounds();
                if (b.hi.x < box.lo.x || b.lo.x > box.hi.x || b.hi.y < box.lo.y || b.lo.y > box.hi.y || b.hi.z < box.lo.z ||
                    b.lo.z > box.hi.z)
                    continue;
                // (a medium transition would hand the ray to another medium inside this one's region)
                eligible = eligible && !other->region_boundary && !other->is_medium_transition();
                near.push_back(other);
            }
            // (built here, before rendering: the only writer)
            if (eligible)
                const_cast<MacrofacetMedium&>(*medium).find_exits(s->exit_level, s->exterior.get(), scene_->add_near_scene(near, box));
        }
    }

    /// Refuses a boundary that does not contain the medium's region: every vertex of a mesh (2048
    /// points of a sphere) must have f >= k sigma and its box must contain the region's, up to the
    /// float rounding of the boundary's coordinates (1e-5 of the region's size).
    static void check_boundary(const SceneObject& o, const Shape& boundary, const MacrofacetMedium& medium) {
        const double level = medium.shell_top();
        mf_vec3 lo, hi;
        if (mf_surface_bounding_box(medium.surface().handle(), &lo, &hi) != MF_OK)
            throw err(o, "mf_surface_bounding_box failed: " + mf_last_error());
        const double tol = 1e-5 * std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, level});
        const Aabb b = boundary.bounds();
        if (b.lo.x > lo.x - level + tol || b.lo.y > lo.y - level + tol || b.lo.z > lo.z - level + tol ||
            b.hi.x < hi.x + level - tol || b.hi.y < hi.y + level - tol || b.hi.z < hi.z + level - tol)
            throw err(o, "does not contain its macrofacet medium's region f < k sigma = " + std::to_string(level) +
                             ": its box is smaller than the mean surface's grown by k sigma");
        std::vector<Vec3> points;
        if (auto* sph = dynamic_cast<const SphereShape*>(&boundary)) {
            const int n = 2048;  // a Fibonacci sphere
            for (int i = 0; i < n; ++i) {
                float z = 1 - (2 * i + 1) / float(n), r = std::sqrt(std::max(0.0f, 1 - z * z)), phi = 2.39996323f * i;
                points.push_back(sph->center() + Vec3(r * std::cos(phi), r * std::sin(phi), z) * sph->radius());
            }
        } else if (auto* mesh = dynamic_cast<const MeshShape*>(&boundary)) {
            points = mesh->mesh().p;
        }
        for (const Vec3& p : points) {
            double f = medium.surface().eval(p, nullptr, nullptr);
            if (f < level - tol)
                throw err(o, "does not contain its macrofacet medium's region f < k sigma = " + std::to_string(level) +
                                 ": at (" + std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) +
                                 ") f = " + std::to_string(f) + " (for a sphere of radius r: a boundary of radius >= r + k "
                                 "sigma; for a mesh: python3 -m macrofacet_mitsuba enclosure)");
        }
    }

    /// The checks of a medium's spatially varying parameters that need its mean surface, and an
    /// sdfgrid's own: the grid must contain the whole medium region f < shell top.
    void check_mean_surface_fields(const MediumParamBag& bag, const Shape& shape) {
        check_fields_on_surface(bag, shape);
        auto* sdf = dynamic_cast<const SdfGridShape*>(&shape);
        if (!sdf) return;
        const SdfGrid& g = sdf->grid();
        const double top = shell_top_bound(bag);
        long long node = g.boundary_node_below(top);
        if (node < 0) return;
        long long i = node % g.nx, j = (node / g.nx) % g.ny, k = node / (g.nx * (long long)g.ny);
        throw Error(shape.loc, "<shape type=\"sdfgrid\">: the medium's region f < " + std::to_string(top) +
                                   " (the shell's top, shell_extent x the largest sigma) reaches the grid's boundary at node (" +
                                   std::to_string(i) + ", " + std::to_string(j) + ", " + std::to_string(k) + ") (f = " +
                                   std::to_string(g.at(int(i), int(j), int(k))) +
                                   "): the SDF grid must contain the whole medium; enlarge it");
    }

    // ------------------------------------------------------------------ emitters
    std::shared_ptr<Emitter> build_emitter(const SceneObject& o, const Shape* shape) {
        skip_if_broken(o);
        std::shared_ptr<Emitter> e;
        const std::string& t = o.type;
        if (t == "area") {
            if (o.child_named("texture", "radiance"))
                throw perr(o, "radiance", "as a texture is not supported (mfrender's area lights emit uniformly)");
            if (!o.has("radiance")) throw err(o, "missing required parameter \"radiance\"");
            e = std::make_shared<AreaEmitter>(shape, nonneg_rgb(o, "radiance", Rgb(1.0f)));
        } else if (t == "point") {
            Vec3 p(0.0f);
            if (o.has("position") && o.has("to_world")) throw err(o, "specify either position or to_world, not both");
            if (o.has("position")) p = o.get_point("position", p);
            else p = o.get_transform("to_world", Mat4()).point(Vec3(0.0f));
            e = std::make_shared<PointEmitter>(p, nonneg_rgb(o, "intensity", Rgb(1.0f)));
        } else if (t == "spot") {
            // Mitsuba's spot: intensity is a constant, texture (optional) must vary over uv
            if (o.child_named("texture", "intensity")) throw perr(o, "intensity", "cannot be spatially varying (as in Mitsuba)");
            if (o.has("texture")) throw perr(o, "texture", "must be a spatially varying texture (as in Mitsuba)");
            std::shared_ptr<const Texture> tex;
            if (const Child* c = o.child_named("texture", "texture")) tex = build_texture(*c->obj);
            float cutoff = o.get_float("cutoff_angle", 20.0f);
            float beam = o.get_float("beam_width", cutoff * 0.75f);
            // Mitsuba projects the texture with tan(cutoff_angle): the cone must stay in front
            float max_cutoff = tex ? 90.0f : 180.0f;
            if (!(cutoff > 0 && cutoff < max_cutoff))
                throw perr(o, "cutoff_angle", tex ? "must lie in (0, 90) degrees with a texture" : "must lie in (0, 180) degrees");
            if (!(beam >= 0 && beam <= cutoff)) throw perr(o, "beam_width", "must lie in [0, cutoff_angle] degrees");
            const float deg = kPi / 180.0f;
            e = std::make_shared<SpotEmitter>(o.get_transform("to_world", Mat4()), nonneg_rgb(o, "intensity", Rgb(1.0f)),
                                              cutoff * deg, beam * deg, tex);
        } else if (t == "projector") {
            // Mitsuba's projector: the perspective sensor's mapping, the image's aspect from the
            // irradiance texture's resolution (1 x 1 for a constant)
            auto irradiance = texture_param(o, "irradiance", Rgb(1.0f));
            auto res = irradiance->resolution();
            float scale = o.get_float("scale", 1.0f);
            if (!(scale >= 0 && std::isfinite(scale))) throw perr(o, "scale", "must be finite and non-negative");
            e = std::make_shared<ProjectorEmitter>(o.get_transform("to_world", Mat4()), fov_tangents(o, res.first, res.second),
                                                   irradiance, scale);
        } else if (t == "directional") {
            Vec3 d(0, 0, 1);
            if (o.has("direction") && o.has("to_world")) throw err(o, "specify either direction or to_world, not both");
            if (o.has("direction")) d = o.get_vector("direction", d);
            else d = o.get_transform("to_world", Mat4()).vector(Vec3(0, 0, 1));
            if (!(length(d) > 0)) throw perr(o, "direction", "must be non-zero");
            e = std::make_shared<DirectionalEmitter>(d, nonneg_rgb(o, "irradiance", Rgb(1.0f)));
        } else if (t == "constant") {
            e = std::make_shared<ConstantEmitter>(nonneg_rgb(o, "radiance", Rgb(1.0f)));
        } else if (t == "envmap") {
            std::string path = resolve_file(o, "filename");
            float scale = o.get_float("scale", 1.0f);
            if (!(scale >= 0)) throw perr(o, "scale", "must be non-negative");
            Mat4 tw = o.get_transform("to_world", Mat4());
            Image img;
            try {
                img = read_exr(path);
            } catch (const Error& ex) {
                throw Error(o.loc, o.describe() + ": " + ex.what());
            }
            for (float v : img.rgb)
                if (v < 0) throw err(o, "environment map \"" + path + "\" has negative pixel values");
            e = std::make_shared<EnvmapEmitter>(std::move(img.rgb), img.width, img.height, scale, tw);
        } else {
            throw err(o, "unsupported emitter plugin \"" + t + "\" (supported: area, point, spot, projector, directional, constant, envmap)");
        }
        o.check_all_used();
        return e;
    }

    // ------------------------------------------------------------------ sensor & integrator
    /// Mitsuba's parse_fov for a perspective sensor (or projector) whose image is width x height:
    /// the tangents of the half field of view along x and y.
    Vec2 fov_tangents(const SceneObject& o, int width, int height) {
        // Mitsuba's parse_fov: fov along fov_axis, or a focal length on 35 mm film (36 x 24 mm),
        // i.e. a diagonal fov of 2 atan(sqrt(36^2 + 24^2) / (2 f)); default focal_length 50mm.
        if (o.has("fov") && o.has("focal_length")) throw err(o, "specify either fov or focal_length, not both");
        float fov;
        std::string axis;
        if (o.has("fov")) {
            fov = o.get_float("fov");
            if (!(fov > 0 && fov < 180)) throw perr(o, "fov", "must lie in (0, 180) degrees");
            axis = o.get_string("fov_axis", "x");
        } else {
            std::string fl = o.get_string("focal_length", "50mm");
            std::string num = fl.size() > 2 && fl.compare(fl.size() - 2, 2, "mm") == 0 ? fl.substr(0, fl.size() - 2) : fl;
            char* end = nullptr;
            double f = std::strtod(num.c_str(), &end);
            if (num.empty() || *end || !(f > 0) || !std::isfinite(f))
                throw perr(o, "focal_length", "must be a positive length in mm such as \"50mm\", got " + quote(fl));
            fov = float(2.0 * std::atan(std::sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2.0 * f)) * 180.0 / 3.14159265358979323846);
            axis = "diagonal";
            if (o.has("fov_axis")) o.get_string("fov_axis", "x");  // Mitsuba ignores it with focal_length
        }
        Vec2 tan_half;
        float aspect = float(width) / float(height);
        float t = std::tan(0.5f * fov * kPi / 180.0f);
        if (axis == "smaller") axis = width <= height ? "x" : "y";
        if (axis == "larger") axis = width >= height ? "x" : "y";
        if (axis == "x") {
            tan_half.x = t;
            tan_half.y = t / aspect;
        } else if (axis == "y") {
            tan_half.y = t;
            tan_half.x = t * aspect;
        } else if (axis == "diagonal") {
            float diag = std::sqrt(aspect * aspect + 1.0f);
            tan_half.x = t * aspect / diag;
            tan_half.y = t / diag;
        } else {
            throw perr(o, "fov_axis", "must be x, y, diagonal, smaller or larger");
        }
        return tan_half;
    }

    void build_sensor(const SceneObject& o) {
        if (o.type != "perspective" && o.type != "orthographic")
            throw err(o, "unsupported sensor plugin \"" + o.type + "\" (supported: perspective, orthographic)");
        Camera& cam = scene_->camera;
        cam.to_world = o.get_transform("to_world", Mat4());
        cam.orthographic = o.type == "orthographic";
        // Mitsuba's perspective (pinhole) reads and ignores focus_distance (only thinlens uses it)
        if (!cam.orthographic && !(o.get_float("focus_distance", 1.0f) > 0)) throw perr(o, "focus_distance", "must be positive");
        cam.near_clip = o.get_float("near_clip", 1e-2f);
        cam.far_clip = o.get_float("far_clip", 1e4f);
        if (!(cam.near_clip > 0 && cam.far_clip > cam.near_clip)) throw err(o, "needs 0 < near_clip < far_clip");

        auto films = o.children_with_tag("film");
        if (films.size() > 1) throw err(o, "has more than one film");
        if (!films.empty()) {
            const SceneObject& f = *films[0]->obj;
            if (f.type != "hdrfilm") throw Error(f.loc, f.describe() + ": unsupported film plugin (supported: hdrfilm)");
            long long w = f.get_int("width", 768), h = f.get_int("height", 576);
            if (w <= 0 || h <= 0 || w > 65536 || h > 65536) throw Error(f.loc, f.describe() + ": invalid film size");
            cam.width = int(w);
            cam.height = int(h);
            // accepted for compatibility; output is always float32 RGB OpenEXR
            std::string pf = f.get_string("pixel_format", "rgb");
            if (pf != "rgb" && pf != "rgba")
                throw perr(f, "pixel_format", "must be rgb or rgba (output is always RGB), got \"" + pf + "\"");
            f.get_string("component_format", "float32");
            std::string ff = f.get_string("file_format", "openexr");
            if (ff != "openexr" && ff != "exr") throw perr(f, "file_format", "must be openexr");
            f.get_bool("sample_border", false);
            auto rf = f.children_with_tag("rfilter");
            if (rf.size() > 1) throw Error(f.loc, f.describe() + ": more than one rfilter");
            if (!rf.empty()) {
                const SceneObject& r = *rf[0]->obj;
                skip_if_broken(r);
                if (r.type == "gaussian") {
                    float sd = r.get_float("stddev", 0.5f);
                    if (!(sd > 0 && sd <= 16)) throw perr(r, "stddev", "must lie in (0, 16] pixels");
                    scene_->filter = ReconstructionFilter::gaussian(sd);
                } else if (r.type == "tent") {
                    float rad = r.get_float("radius", 1.0f);
                    if (!(rad > 0 && rad <= 64)) throw perr(r, "radius", "must lie in (0, 64] pixels");
                    scene_->filter = ReconstructionFilter::tent(rad);
                } else if (r.type == "box") {
                    scene_->filter = ReconstructionFilter::box();
                } else {
                    throw Error(r.loc, r.describe() + ": unsupported reconstruction filter (supported: gaussian, tent, box)");
                }
                r.check_all_used();
            }
            f.check_all_used();
        }
        if (!cam.orthographic) {
            const Vec2 tan_half = fov_tangents(o, cam.width, cam.height);
            cam.tan_half_x = tan_half.x;
            cam.tan_half_y = tan_half.y;
        }
        auto samplers = o.children_with_tag("sampler");
        if (samplers.size() > 1) throw err(o, "has more than one sampler");
        if (!samplers.empty()) {
            const SceneObject& s = *samplers[0]->obj;
            if (s.type != "independent")
                throw Error(s.loc, s.describe() + ": unsupported sampler plugin (supported: independent)");
            long long spp = s.get_int("sample_count", 4);
            if (spp <= 0) throw perr(s, "sample_count", "must be positive");
            scene_->spp = int(std::min<long long>(spp, 1 << 24));
            long long seed = s.get_int("seed", 0);
            scene_->seed = uint64_t(seed);
            s.check_all_used();
        } else {
            scene_->spp = 4;
        }
        auto meds = o.children_with_tag("medium");
        if (meds.size() > 1) throw err(o, "has more than one medium");
        if (!meds.empty()) {
            if (is_macrofacet(*meds[0]->obj))
                throw Error(meds[0]->loc, o.describe() + ": a sensor cannot be inside a macrofacet medium");
            scene_->camera_medium = build_medium(*meds[0]->obj);
        }
        o.check_all_used();
    }

    void build_integrator(const SceneObject& o) {
        if (o.type == "moment") {
            // Mitsuba's moment renders its nested integrator(s) and writes, after the R, G, B of
            // the (first) nested image, each image and its per-pixel second moment as AOVs.
            auto nested = o.children_with_tag("integrator");
            if (nested.size() != 1) throw err(o, "needs exactly one nested <integrator> (mfrender renders one image)");
            o.check_all_used();
            const SceneObject& inner = *nested[0]->obj;
            skip_if_broken(inner);
            build_integrator(inner);
            if (report_)
                report_->warnings.push_back(o.loc.str() + ": " + o.describe() + ": writing the R, G, B image of the nested " +
                                            inner.describe() + "; the moment AOV channels are not written");
            return;
        }
        IntegratorSettings s;
        s.name = o.type;
        if (o.type == "direct") {
            // Mitsuba's direct: emission seen directly plus one bounce of direct light from
            // emitter_samples and bsdf_samples (shading_samples sets both), combined by MIS and
            // ignoring media -- the path estimator with max_depth 2. mfrender takes one sample of
            // each strategy (0 leaves it out): the same image in expectation, not the same noise.
            long long shading = o.get_int("shading_samples", 1);
            long long n_em = o.get_int("emitter_samples", shading), n_bsdf = o.get_int("bsdf_samples", shading);
            for (const char* name : {"shading_samples", "emitter_samples", "bsdf_samples"})
                if (o.has(name) && !(o.get_int(name, 1) == 0 || o.get_int(name, 1) == 1))
                    throw perr(o, name, "must be 0 or 1 in mfrender (more samples per bounce are not supported)");
            if (n_em == 0 && n_bsdf == 0) throw err(o, "emitter_samples and bsdf_samples are both 0 (nothing to render)");
            s.volumetric = false;
            s.max_depth = 2;
            s.light_sampling = n_em == 0 ? LightSampling::BsdfOnly : n_bsdf == 0 ? LightSampling::EmitterOnly : LightSampling::Mis;
            s.hide_emitters = o.get_bool("hide_emitters", false);
            o.check_all_used();
            scene_->integrator = s;
            return;
        }
        if (o.type == "volpath") s.volumetric = true;
        else if (o.type == "path") s.volumetric = false;
        else throw err(o, "unsupported integrator plugin \"" + o.type + "\" (supported: volpath, path, direct, moment)");
        long long md = o.get_int("max_depth", -1);
        if (md < -1) throw perr(o, "max_depth", "must be -1 (unbounded) or >= 0");
        long long rr = o.get_int("rr_depth", 5);
        if (rr < 0) throw perr(o, "rr_depth", "must be >= 0");
        s.max_depth = int(std::min<long long>(md, 1 << 20));
        s.rr_depth = int(std::min<long long>(rr, 1 << 20));
        s.hide_emitters = o.get_bool("hide_emitters", false);
        o.check_all_used();
        scene_->integrator = s;
    }
};

}  // namespace

std::unique_ptr<Scene> build_scene(const ParsedScene& parsed, const BuildOptions& opts, BuildReport* report,
                                   ErrorSink* errors) {
    Builder b(opts, report);
    ErrorSink local;
    std::unique_ptr<Scene> scene = b.build(parsed, errors ? *errors : local);
    local.raise();
    if (!scene && errors && errors->empty()) throw Error("the scene could not be built");
    return scene;
}

const char* supported_subset_text() {
    return R"(Supported Mitsuba 3 XML subset (<scene version="x.y.z">, 0.x-3.x; pre-2.0 scenes are upgraded
in memory as Mitsuba does: camelCase names, lookAt, diffuseReflectance):
  structure   <default name value>, $name substitution, -D name=value, <include filename> (anywhere),
              <path value> (resolver order: <path> folders latest first, the scene's folder, the
              including file's folder, the working directory), id="..." and <ref id>/<ref name id>
              (forward references too), <alias id as>
  properties  integer float boolean string rgb vector point transform
              spectrum type="srgb" (<rgb name="color">: the colour, bounded like an <rgb>)
              spectrum (a constant, wavelength:value lists or a .spd file, converted to linear sRGB
              as Mitsuba 3's RGB variants do: CIE 1931 and D65 for reflectances, Y-normalised emission)
              <rgb> outside emitters must lie in [0, 1] (Mitsuba's RGB variants refuse it) except
              eta, k, int_ior, ext_ior: use <float> or rgb with a scale (e.g. sigma_t)
  transforms  translate, rotate (axis as given, like Mitsuba: a non-unit axis also scales), scale,
              matrix (16 or 9 values, row-major), lookat (origin, target, up; without up: the
              first axis of Mitsuba's coordinate_system(direction)); applied in order
  shapes      obj (flip_tex_coords), ply (ascii / binary_little_endian), serialized (shape_index;
              zlib), sphere (center, radius), rectangle, cube, disk, cylinder (radius, p0, p1;
              open ends), shapegroup + instance (to_world; no emitters, media or nesting),
              sdfgrid (filename .vol | .vdb with grid, normals; only as the mean surface of a
              macrofacet/gpis medium, validated; never rendered as a surface of its own);
              to_world, flip_normals,
              face_normals; nested or referenced bsdf, area emitter (nested, or a top-level
              <emitter type="area" id> referenced by the shape), <medium name="interior|exterior">
              uv and dp/du as Mitsuba 3 (anisotropic roughness follows dp/du: Frame::shading)
  textures    wherever listed below as (tex): a constant, <texture type="checkerboard"> (color0,
              color1, to_uv), <texture type="bitmap"> (filename .png/.jpg/.exr, filter_type
              bilinear|nearest, wrap_mode repeat|mirror|clamp, raw, to_uv) or <texture
              type="mesh_attribute"> (name vertex_color | face_color: a PLY's r, g, b as stored;
              scale), nested with name="param" or <ref name="param" id>
  bsdfs       diffuse (reflectance (tex)), conductor (material | eta,k; specular_reflectance (tex)),
              roughconductor (distribution beckmann|ggx|gtr, alpha | alpha_u,alpha_v, material |
              eta,k, specular_reflectance (tex), sample_visible; mfrender extension: shadowing
              separable (default, Mitsuba's G1*G1) | height_correlated (1/(1+Lambda_i+Lambda_o));
              from the library: gtr's gamma, lambda exact|dimov, and the microsurface transform
              stretch | transform_xx,_xy,_yx,_yy of any distribution (seeds/001)),
              dielectric, thindielectric (int_ior, ext_ior: number or name; specular_reflectance,
              specular_transmittance), roughdielectric (the same, both (tex), plus distribution,
              alpha | alpha_u,alpha_v, sample_visible), plastic, roughplastic (int_ior, ext_ior,
              diffuse_reflectance (tex), specular_reflectance ((tex) when rough), nonlinear;
              rough: distribution, isotropic alpha, sample_visible), null, twosided (one or two
              bsdfs), mask (opacity (tex), one nested bsdf: absent with probability 1 - opacity),
              normalmap (normalmap (tex, values 2c - 1 in the shading frame), one nested bsdf,
              use_shadowing_function; Mitsuba 3.9.1's side rules and Conty Estevez 2019 shadowing)
              conductor materials: none, Ag, Al, Au, Cr, Cu
  media       homogeneous (sigma_t, albedo, scale; <phase type="isotropic|hg"> with g)
              heterogeneous (sigma_t, albedo: constants or <volume> constvolume | gridvolume;
              scale; phase; the medium fills the box of sigma_t's volume, as in Mitsuba)
              macrofacet (as the interior of its mean-surface shape; the library's parameter
              names, whose types, ranges and defaults README.md "Medium parameters" lists:
              sigma | variance, shell_extent, distribution, alpha, alpha_u/v/z, lengthscale*,
              gamma, lambda, stretch | transform_*, micro_bsdf, material | eta,k,
              specular_reflectance, reflectance, vndf_sampling, mixture_ratio);
              sigma, variance, alpha*, lengthscale*, specular_reflectance, reflectance and
              the anisotropy may be a nested <volume> (constvolume: value; gridvolume:
              filename .vol | .vdb with grid, to_world, filter_type trilinear|nearest,
              wrap_mode clamp|repeat|mirror, use_grid_bbox) or <texture>; or in the form that
              Mitsuba 3 with the macrofacet plugin also reads: the medium nests its mean
              surface as <shape name="mean_surface"> (sphere or mesh) and the shapes whose
              interior it is are boundaries (<bsdf type="null"/>, containing f < k sigma)
              gpis (realization-based ground truth; as the interior of its mean-surface
              shape; of README.md "Medium parameters": sigma | variance, shell_extent,
              distribution gpss|beckmann, alpha*, lengthscale*, material | eta,k,
              specular_reflectance, memory renewal|renewal_plus, step_correlation)
  emitters    area (radiance), point (position | to_world, intensity), spot (to_world,
              intensity, cutoff_angle, beam_width, texture), projector (to_world, irradiance (tex),
              scale, fov | focal_length, fov_axis), directional
              (direction | to_world, irradiance), constant (radiance),
              envmap (filename: lat-long OpenEXR, scale, to_world)
  sensor      perspective (fov + fov_axis x|y|diagonal|smaller|larger, or focal_length such as
              "50mm" on 35 mm film (Mitsuba's default when neither is given), focus_distance
              (read, no effect on a pinhole), to_world, near_clip, far_clip), orthographic (to_world
              scales the window x in [-1, 1], y in [-1/aspect, 1/aspect]; near_clip, far_clip);
              with hdrfilm (width,
              height, rfilter gaussian (stddev; the default, 0.5) | tent (radius) | box) and
              independent sampler (sample_count, seed)
  integrators volpath, path (max_depth, rr_depth, hide_emitters), direct (shading_samples,
              emitter_samples, bsdf_samples: 0 or 1; hide_emitters), moment around one of them
              (its R, G, B image; the moment AOVs are not written)
Unknown elements, plugin types or parameters are errors; every problem of a file is listed.
Not supported (refused with the element's file:line): other plugins, e.g. principled,
blendbsdf, bumpmap, emissive media.
Reader limits: XML elements (and reference chains) nested at most 64 deep; <include> at most
15 deep; an XML file at most 64 MiB, all of a scene's XML at most 256 MiB, regular files only
(devices and pipes are refused); an attribute at most 1 MiB after $substitution; at most 100
problems are listed; values echoed in messages are cut to 64 characters.
)";
}

}  // namespace mf
