// macrofacet for Mitsuba 3 — <medium type="macrofacet">: a Gaussian-process statistical surface
// as an exponential medium (seeds/000), through the library's C ABI, for Mitsuba's volpath and
// volpathmis in scalar_rgb.
//
// Scene description (README "Use in Mitsuba 3"): the medium's parameters are the README table's;
// those that may vary in space may be nested <volume>s or <texture>s instead of numbers
// (varying_params.h); the mean surface is a shape nested in the medium as <shape
// name="mean_surface"> (Mitsuba loads it; it is not part of the scene); the scene's shape whose
// interior is this medium is the boundary through which rays enter: it must contain the region
// f < k sigma and have a null BSDF (the sphere of radius r + k sigma, or for a mesh the enclosure
// that `python3 -m macrofacet_mitsuba enclosure` writes). mfrender reads the same file.
//
// Tracking: the library's, as in mfrender. Mitsuba's Medium::sample_interaction (not virtual)
// calls, on one thread and in this order, intersect_aabb(ray) for the interval [mint, maxt] of
// the ray in the medium, get_majorant(mi) for the rate of an exponential step from mint, and
// get_scattering_coefficients(mi) at the step's end; volpath then accepts the event with
// probability sigma_t / majorant (else a null collision, weighted sigma_n / majorant in shadow
// rays). Here intersect_aabb runs mf_track_free_flight along the ray (delta tracking with the
// library's closed-form majorants: exact for the density that grows without bound below the
// mean surface, no core or cut needed; with varying parameters the library asks the medium's
// field for them at tentative collisions and for their bounds along each segment, and reports
// them with the collision for the phase function) and reports the sampled collision as the start of the
// interval, or no interval when the ray passes; get_majorant then returns kCertain, so large
// that the exponential step is below float resolution (the event lands on the collision), and
// get_scattering_coefficients confirms the event with sigma_t = sigma_s = kCertain, sigma_n = 0.
// volpath's estimators reduce to the library's: a collision at the tracked distance with weight
// 1 (the flakes' albedo is in the phase function), and for shadow rays a transmittance of 0 or 1
// (the track-length estimator: unbiased, noisier than mfrender's ratio tracking).
//
// get_majorant sees only mi.wi, so the collision travels from intersect_aabb in a thread-local
// record naming the medium and the direction. A call sequence the medium did not prepare (not
// Mitsuba 3.9.1's sample_interaction, e.g. a direct call from Python) gets an empty medium and is
// counted (to_string reports it). The tracking seed is a hash of the ray (origin, direction,
// maxt) and the medium's id: renders are deterministic for Mitsuba's seed, whatever the threads.
// Library errors at render time are counted and give an empty medium for that ray instead of an
// exception inside Mitsuba's render loop.
#pragma once

#include <mitsuba/core/properties.h>
#include <mitsuba/render/medium.h>

#include <limits>
#include <string>

#include "library.h"
#include "params.h"
#include "phase.h"
#include "shape_geometry.h"
#include "varying_params.h"

namespace mfmi {

using namespace mitsuba;  // Mitsuba's MI_IMPORT_* macros name its types unqualified

/// The collision that intersect_aabb sampled for get_majorant and get_scattering_coefficients.
struct PendingCollision {
    uint64_t medium_id = 0;
    float wi[3] = {0, 0, 0};
};
inline thread_local PendingCollision t_pending;

template <typename Float, typename Spectrum>
class MacrofacetMedium final : public Medium<Float, Spectrum> {
public:
    MI_IMPORT_BASE(Medium, m_is_homogeneous, m_has_spectral_extinction, m_phase_function)
    MI_IMPORT_TYPES(PhaseFunction, Shape, Volume, Texture)
    static_assert(!dr::is_jit_v<Float>, "the macrofacet plugin supports scalar variants only");

    /// The majorant that makes Mitsuba's exponential step vanish: -log(1 - u) / kCertain < 2e-17
    /// for every float u < 1, far below a float's resolution at any collision distance, while
    /// its square stays finite in float (integrators may multiply two rates).
    static constexpr float kCertain = 1e18f;

    MacrofacetMedium(const Properties& props) : Base(props) {
        const std::string id(props.id());
        const std::string label = id.empty() ? "<medium type=\"macrofacet\">" : "<medium type=\"macrofacet\" id=\"" + id + "\">";
        try {
            // read by Mitsuba's Medium base class; not a macrofacet parameter (mfrender always
            // samples emitters), so a file with it would not render in both
            if (props.has_property("sample_emitters"))
                throw std::runtime_error("parameter \"sample_emitters\" is not supported (next-event estimation is always used)");
            Shape* mean = nullptr;
            std::vector<NestedParam> nested;
            for (const auto& prop : props.objects()) {
                const std::string name(prop.name());
                if (prop.template try_get<PhaseFunction>())
                    throw std::runtime_error("takes no nested <phase>: the flakes define the phase function (micro_bsdf, "
                                             "material, eta, k, reflectance, ...)");
                if (name == kMeanSurface) {
                    mean = prop.template try_get<Shape>();
                    if (!mean) throw std::runtime_error(std::string("\"") + kMeanSurface + "\" must be a <shape>");
                } else if (prop.template try_get<Volume>() || prop.template try_get<Texture>()) {
                    nested.push_back(NestedParam{name, ref<Object>(prop.template try_get<Object>())});
                } else {
                    throw std::runtime_error("unexpected nested object \"" + name + "\" (a macrofacet medium takes one <shape name=\"" +
                                             kMeanSurface + "\"> and <volume>s or <texture>s of the parameters that vary in space)");
                }
            }
            if (!mean)
                throw std::runtime_error(std::string("needs its mean surface: nest <shape type=\"sphere\" name=\"") +
                                         kMeanSurface + "\">, a mesh shape (obj, ply, ...) or an sdfgrid with name=\"" + kMeanSurface + "\"");
            bool diffuse = false;
            if (props.has_property("micro_bsdf") && props.type("micro_bsdf") == Properties::Type::String) {
                diffuse = props.get<std::string>("micro_bsdf") == "diffuse";
                props.mark_queried("micro_bsdf", false);  // params_of() passes it on to the library
            }
            ::mf::MediumParamBag bag;
            bag.type = "macrofacet";
            bag.id = id;
            ParamsPtr params = params_of(props, &bag);
            // the base medium takes the constvolumes' numbers and every varying parameter at its
            // largest value (mfrender's base_bag, cpp_host/src/medium_field.h): those after the
            // numbers params_of has set
            const size_t given = bag.params.size();
            read_varying_params<Float, Spectrum>(nested, &bag);
            const ::mf::MediumParamBag base = ::mf::base_bag(bag);
            for (size_t i = given; i < base.params.size(); ++i) {
                const auto& [name, v] = base.params[i];
                // mfrender's bag keeps rgb in float: each channel as the number written (as_written)
                const double rgb[3] = {as_written(v.rgb.r), as_written(v.rgb.g), as_written(v.rgb.b)};
                const mf_status st = v.kind == ::mf::ParamValue::Kind::Rgb ? mf_params_set_rgb(params.get(), name.c_str(), rgb)
                                                                           : mf_params_set_float(params.get(), name.c_str(), v.f);
                if (st != MF_OK) throw std::runtime_error("parameter \"" + name + "\": " + library_error());
            }
            mf_medium* medium = nullptr;
            if (mf_medium_new(params.get(), &medium) != MF_OK) throw std::runtime_error(library_error());
            std::unique_ptr<mf_medium, MediumDeleter> owned(medium);
            VaryingField field;
            field.fields = bag.fields;
            field.library = ::mf::library_field_of(bag);
            double top = 0;
            check(mf_medium_shell_top(medium, &top), "mf_medium_shell_top");
            // the mean surface, built for this medium's reach (its largest shell top)
            std::shared_ptr<const MeanSurface> surface;
            try {
                surface = mean_surface_of(mean, top);
            } catch (const std::exception& e) {
                throw std::runtime_error(std::string("<shape name=\"") + kMeanSurface + "\">: " + e.what());
            }
            check_fields_on_surface(field.fields.get(), *surface, top);
            state_ = std::make_shared<const MediumState>(owned.release(), std::move(surface), std::move(field), diffuse, label,
                                                         mix64(std::hash<std::string>()(id)));
        } catch (const std::exception& e) {
            Throw("%s: %s", label, e.what());
        }
        m_is_homogeneous = false;
        m_has_spectral_extinction = false;  // grey: the flakes' colour is in the phase function
        m_phase_function = new MacrofacetPhase<Float, Spectrum>(state_);
    }

    std::tuple<Mask, Float, Float> intersect_aabb(const Ray3f& ray) const override {
        const Float inf = dr::Infinity<Float>;
        PendingCollision& pending = t_pending;
        pending.medium_id = 0;
        const float key[7] = {ray.o.x(), ray.o.y(), ray.o.z(), ray.d.x(), ray.d.y(), ray.d.z(), ray.maxt};
        const double t_max = ray.maxt >= dr::Largest<Float> ? std::numeric_limits<double>::infinity() : double(ray.maxt);
        const mf_track_query query{mf_vec3{ray.o.x(), ray.o.y(), ray.o.z()}, unit(ray.d.x(), ray.d.y(), ray.d.z()), t_max,
                                   hash_floats(key, 7, state_->seed_salt), 0.0, 0.0, 0};
        mf_collision c;
        if (mf_track_free_flight(state_->medium, state_->surface->handle(), state_->field_handle(), state_->field_user_data(), &query, &c) !=
            MF_OK) {
            state_->errors.fetch_add(1, std::memory_order_relaxed);
            return {false, inf, inf};
        }
        state_->count(c.stats, c.scattered);
        if (!c.scattered) return {false, inf, inf};
        const Float t = Float(c.t);
        const Point3f p = ray(t);  // Mitsuba's position of the event (see kCertain)
        const float pf[3] = {p.x(), p.y(), p.z()};
        state_->remember(pf, c.frame, c.local);
        pending.medium_id = state_->id;
        pending.wi[0] = -ray.d.x();
        pending.wi[1] = -ray.d.y();
        pending.wi[2] = -ray.d.z();
        return {true, t, inf};
    }

    UnpolarizedSpectrum get_majorant(const MediumInteraction3f& mi, Mask active) const override {
        if (active && !prepared(mi)) {
            state_->unprepared.fetch_add(1, std::memory_order_relaxed);
            return UnpolarizedSpectrum(0.f);
        }
        return UnpolarizedSpectrum(kCertain);
    }

    std::tuple<UnpolarizedSpectrum, UnpolarizedSpectrum, UnpolarizedSpectrum>
    get_scattering_coefficients(const MediumInteraction3f& mi, Mask active) const override {
        const UnpolarizedSpectrum zero(0.f);
        if (!active) return {zero, zero, zero};
        if (!prepared(mi)) {
            state_->unprepared.fetch_add(1, std::memory_order_relaxed);
            return {zero, zero, zero};
        }
        t_pending.medium_id = 0;  // consumed
        return {UnpolarizedSpectrum(kCertain), zero, UnpolarizedSpectrum(kCertain)};
    }

    std::string to_string() const override { return "MacrofacetMedium[" + state_->label + ", " + state_->report() + "]"; }

    MI_DECLARE_CLASS(MacrofacetMedium)

private:
    /// True when intersect_aabb sampled a collision on mi's ray for this medium (file comment).
    bool prepared(const MediumInteraction3f& mi) const {
        const PendingCollision& pending = t_pending;
        return pending.medium_id == state_->id && pending.wi[0] == mi.wi.x() && pending.wi[1] == mi.wi.y() &&
               pending.wi[2] == mi.wi.z();
    }

    std::shared_ptr<const MediumState> state_;
};

}  // namespace mfmi
