// mfhost — volumetric path tracer (see integrator.h).
#include "integrator.h"

#include <utility>

namespace mf {

namespace {
constexpr int kMaxNullCrossings = 1024;

/// A thread's medium-event records, reused from path to path and bounce to bounce (building one
/// 264-byte record per path and two per bounce cost a thin shell's render about 2 %): a record is
/// read only after a flight that scattered wrote it (Medium::sample_free_flight says what it
/// writes), the last event only when the ray leaves one. Li passes them round by pointer: the
/// candidate that wins becomes the nearest, the nearest that scatters the last event, and the
/// record given up takes the freed role, with no copy.
struct EventRecords {
    MediumInteraction records[3];
};
thread_local EventRecords event_records;
}  // namespace

template <class Unblocked>
Rgb PathIntegrator::shadow_transmittance(Vec3 o, const Vec3& d, float dist, const Medium* medium,
                                         const MediumInteraction* from, Sampler& sampler,
                                         const Scene::ShadowRoulette& kept, Unblocked&& unblocked) const {
    const bool vol = scene_.integrator.volumetric;
    // The roulette's weight, until its medium's estimate takes it (applied once, whatever the
    // ray meets).
    double pending = kept.survival;
    auto transmittance_of = [&](const Medium& m, const Ray& r, float seg) {
        if (&m != kept.medium || pending == 1.0) return m.transmittance(r, seg, sampler);
        pending = 1.0;
        return m.transmittance_kept(r, seg, sampler, kept.survival);
    };
    auto weighted = [&](const Rgb& T) { return pending == 1.0 ? T : T * float(1.0 / pending); };
    Rgb T(1.0f);
    for (int i = 0; i < kMaxNullCrossings; ++i) {
        Ray r(o, d, 0.0f, dist);
        SurfaceHit h;
        // A medium that finds the exit itself is cast against the shapes near it only (see Li)
        const bool to_exit = vol && medium && medium->finds_exits();
        bool hit = to_exit ? scene_.intersect_near(medium->near_scene(), r, &h) : scene_.intersect(r, &h);
        // Mitsuba's volpath sees through a mask with its transparency (eval_null_transmission);
        // its path tests visibility, which any surface blocks (the mask's null events are Dirac
        // then: emitters reached through it count fully, see Li). A surface that passes nothing
        // ends the ray before any medium is tracked to it: the media's estimates would be
        // multiplied by 0 (on the thin sphere anchor a third of the tracked shadow rays).
        float pass = 1.0f;
        if (hit && !h.shape->bsdf->is_null()) {
            pass = vol ? h.shape->bsdf->transparency(h.texture_point()) : 0.0f;
            if (!(pass > 0)) return Rgb(0.0f);
        }
        if (i == 0 && !unblocked()) return Rgb(0.0f);
        float seg = hit ? h.t : dist;
        if (vol) {
            bool exited = false;
            if (to_exit) {
                float t_end;
                T *= medium->transmittance_to_exit(r, seg, i == 0 ? from : nullptr, sampler, &t_end);
                exited = t_end < seg;
                if (exited) seg = t_end;
            } else if (medium) {
                T *= transmittance_of(*medium, r, seg);
            }
            for (const SuperposedMedium& m : scene_.superposed_media()) {
                if (T.is_black()) break;
                if (m.medium() == kept.medium && pending != 1.0) {
                    pending = 1.0;
                    T *= m.transmittance_kept(r, seg, sampler, kept.survival);
                } else {
                    T *= m.transmittance(r, seg, sampler);
                }
            }
            if (T.is_black()) return T;
            if (exited) {  // left the region before any hit: on from there, outside
                o = o + d * seg;
                if (std::isfinite(dist)) dist -= seg;
                medium = medium->exterior();
                continue;
            }
        }
        if (!hit) return weighted(T);
        T *= pass;
        if (h.shape->is_medium_transition()) medium = h.shape->target_medium(h.ng, d);
        o = offset_ray_origin(h.p, h.ng, d);
        if (std::isfinite(dist)) {
            dist -= h.t;
            if (dist <= 0) return weighted(T);
        }
    }
    return Rgb(0.0f);
}

Rgb PathIntegrator::shadow_transmittance(Vec3 o, const Vec3& d, float dist, const Medium* medium,
                                         Sampler& sampler) const {
    // (Without opaque cores, the weight is a constant the compiler folds away.)
    if (scene_.integrator.volumetric && scene_.has_opaque_cores()) {
        const Scene::ShadowRoulette kept = scene_.next_event_roulette(o, d, dist, sampler);
        if (!(kept.survival > 0)) return Rgb(0.0f);
        return shadow_transmittance(o, d, dist, medium, nullptr, sampler, kept, [] { return true; });
    }
    return shadow_transmittance(o, d, dist, medium, nullptr, sampler, Scene::ShadowRoulette{}, [] { return true; });
}

Rgb PathIntegrator::Li(Ray ray, const Medium* medium, Sampler& sampler) const {
    const IntegratorSettings& cfg = scene_.integrator;
    const bool vol = cfg.volumetric;
    if (!vol) medium = nullptr;
    const auto& emitters = scene_.emitters();
    const float sel_pdf = emitters.empty() ? 0.0f : 1.0f / float(emitters.size());

    Rgb L(0.0f), beta(1.0f);
    // Hero channel for chromatic free flights, and the product of per-channel pdf ratios
    // (see Medium::sample_free_flight); the effective throughput is beta / avg(ratio).
    const int hero = std::min(int(sampler.next_1d() * 3.0f), 2);
    Rgb ratio(1.0f);
    auto throughput = [&]() { return beta / ratio.average(); };
    float eta_scale = 1.0f;
    int depth = 0;            // number of scattering events so far
    bool prev_delta = true;   // last direction came from a Dirac lobe (or the camera)
    float prev_pdf = 0.0f;    // its solid-angle pdf
    Vec3 prev_p = ray.o;      // where it was sampled
    int null_crossings = 0;
    MediumInteraction* last_event = &event_records.records[0];  // the last scattering event in a medium
    bool from_medium_event = false;  // the current ray leaves last_event (the medium's `from`)
    MediumInteraction* mi = &event_records.records[1];    // a bounce's nearest collision so far
    MediumInteraction* mi_m = &event_records.records[2];  // one medium's collision

    // MIS weights of the two ways to reach a non-delta emitter from a non-delta vertex
    // (LightSampling): next-event estimation (light_pdf) and BSDF / phase sampling (scatter_pdf).
    // Delta emitters are reached by NEE only (weight 1 whatever the setting).
    const bool nee_non_delta = cfg.light_sampling != LightSampling::BsdfOnly;
    auto nee_weight = [&](float light_pdf, float scatter_pdf) {
        return cfg.light_sampling == LightSampling::Mis ? power_heuristic(light_pdf, scatter_pdf) : 1.0f;
    };
    auto hit_weight = [&](float light_pdf) {
        if (prev_delta) return 1.0f;  // the camera or a Dirac lobe: emitter sampling cannot find this path
        switch (cfg.light_sampling) {
            case LightSampling::Mis: return power_heuristic(prev_pdf, light_pdf);
            case LightSampling::BsdfOnly: return 1.0f;
            case LightSampling::EmitterOnly: break;
        }
        return 0.0f;
    };

    // The next-event ray's roulette (IntegratorSettings::shadow_roulette): the probability with
    // which it is kept, or 0 when it is not (a number is drawn only for the rays it applies to).
    // The probability is rounded up to the uniforms' grid of 2^-24, so that it is exactly the
    // chance of `u < q` (a smaller one would be kept at u = 0 only, with too large a weight).
    auto shadow_survival = [&](const Rgb& f, float w, float light_pdf) -> float {
        const float g = f.max() * w / light_pdf;
        if (!(g < cfg.shadow_roulette)) return 1.0f;
        const float q = std::ceil(g / cfg.shadow_roulette * 0x1p24f) * 0x1p-24f;
        return sampler.next_1d() < q ? q : 0.0f;
    };

    // Next-event estimation: uniform emitter choice, MIS against eval_pdf.
    auto direct = [&](const Vec3& origin, const Medium* m, const MediumInteraction* from, const Vec3& ref, auto&& eval) -> Rgb {
        if (emitters.empty()) return Rgb(0.0f);
        size_t idx = std::min(size_t(sampler.next_1d() * float(emitters.size())), emitters.size() - 1);
        Vec2 u = sampler.next_2d();
        EmitterSample es;
        if (!emitters[idx]->sample_li(ref, u, &es)) return Rgb(0.0f);
        if (es.Li.is_black() || !(es.pdf > 0) || (!es.delta && !nee_non_delta)) return Rgb(0.0f);
        float dist = std::isfinite(es.dist) ? es.dist * (1.0f - 1e-4f) : kInf;
        // A shell's opaque core and its depth roulette first (Scene::next_event_roulette); then
        // the phase value after the shadow ray's first cast, before any tracking: a ray that
        // meets an opaque surface at once (towards the floor under a sphere) needs neither, and
        // a value of 0 (often, below a height-field shell's tangent plane) spares the tracking.
        const Scene::ShadowRoulette kept = vol && scene_.has_opaque_cores()
                                               ? scene_.next_event_roulette(origin, es.wi, dist, sampler)
                                               : Scene::ShadowRoulette{};
        if (!(kept.survival > 0)) return Rgb(0.0f);
        const float light_pdf = es.pdf * sel_pdf;
        float f_pdf = 0.0f, w = 1.0f, survival = 1.0f;
        Rgb f(0.0f);
        Rgb T = shadow_transmittance(origin, es.wi, dist, m, from, sampler, kept, [&] {
            f = eval(es.wi, &f_pdf);
            if (f.is_black()) return false;
            w = es.delta ? 1.0f : nee_weight(light_pdf, f_pdf);
            survival = shadow_survival(f, w, light_pdf);
            return survival > 0;
        });
        if (T.is_black()) return Rgb(0.0f);
        return f * es.Li * T * (w / light_pdf / survival);
    };

    auto russian_roulette = [&]() -> bool {
        if (depth < cfg.rr_depth) return true;
        float q = std::min(throughput().max() * eta_scale, 0.95f);
        if (!(sampler.next_1d() < q)) return false;
        beta = beta / q;
        return true;
    };

    while (true) {
        // Inside a medium that finds the ray's exit itself (Medium::finds_exits), the ray is cast
        // against the shapes near its region only: not for the boundary's exit, then beyond; and
        // only after the flight, up to where it ended (below).
        const bool to_exit = vol && medium && medium->finds_exits();
        SurfaceHit hit;
        bool found = !to_exit && scene_.intersect(ray, &hit);

        // ---- media: free flights up to the surface (or infinity). The superposed media and the
        // current one are independent exponential flights: the nearest collision wins, so each is
        // sampled up to the nearest so far (SuperposedMedium, scene.h).
        const MediumInteraction* from = from_medium_event ? last_event : nullptr;
        from_medium_event = false;
        // (A ray that meets no medium skips their flights, weights and renormalisation.)
        if (vol && (medium || scene_.may_enter_superposed(ray))) {
            Rgb w(1.0f), pr(1.0f);
            float tmax = found ? hit.t : kInf;
            const Medium* scattering = nullptr;
            bool exited = false;  // the ray left the region before the near shapes' hit
            if (to_exit) {
                // The flight first, unbounded: a free flight is memoryless, so one cut at the
                // nearest shape is this one with its collision beyond the shape dropped. The near
                // shapes are then cast against only up to its collision or exit, most often a
                // box test (on bench/anchor.xml's torus, whose floor is near, these casts went
                // from 12.5 M to 7.2 M instructions). Its collision, or its exit, or the shape
                // bounds the superposed media's flights.
                float t_end;
                const bool collided = medium->sample_free_flight_to_exit(ray, kInf, from, sampler, mi_m, &t_end);
                const float reach = std::min(collided ? mi_m->t : t_end, ray.tmax);
                found = scene_.intersect_near(medium->near_scene(), Ray(ray.o, ray.d, ray.tmin, reach), &hit);
                if (found) {
                    tmax = hit.t;
                } else if (collided) {
                    std::swap(mi, mi_m);
                    tmax = mi->t;
                    scattering = medium;
                } else if (t_end < tmax) {
                    tmax = t_end;
                    exited = true;
                }
            }
            // One medium's flight (a Medium or a SuperposedMedium) up to the nearest collision so
            // far; `from` goes to the medium whose event the ray leaves.
            auto fly = [&](const auto& flight, const Medium* owner) {
                Rgb w_m, pr_m;
                if (flight.sample_free_flight(ray, tmax, from && from->medium == owner ? from : nullptr, hero, sampler, mi_m, &w_m, &pr_m)) {
                    std::swap(mi, mi_m);
                    tmax = mi->t;
                    scattering = owner;
                }
                w *= w_m;
                pr *= pr_m;
            };
            for (const SuperposedMedium& m : scene_.superposed_media()) fly(m, m.medium());
            if (medium && !to_exit) fly(*medium, medium);
            beta *= w;
            ratio *= pr;
            if (beta.is_black() || !beta.finite() || !(ratio.average() > 0)) break;
            {   // renormalise so that avg(ratio) = 1 (throughput unchanged, no overflow)
                float a = ratio.average();
                beta = beta / a;
                ratio = ratio / a;
            }
            if (scattering) {
                if (cfg.max_depth >= 0 && depth + 1 >= cfg.max_depth) break;
                const PhaseFunction& ph = scattering->phase();
                Vec3 wo = -ray.d;
                if (!ph.is_delta())
                    L += throughput() * direct(mi->p, medium, mi, mi->p, [&](const Vec3& wi, float* pdf) {
                        return ph.eval_pdf(*mi, wo, wi, pdf);
                    });
                Vec3 wi;
                float pdf;
                Rgb pw;
                if (!ph.sample(*mi, wo, sampler, &wi, &pdf, &pw)) break;
                beta *= pw;
                prev_delta = ph.is_delta();
                prev_pdf = pdf;
                prev_p = mi->p;
                ray = Ray(mi->p, wi);
                std::swap(last_event, mi);
                from_medium_event = true;
                ++depth;
                if (!russian_roulette()) break;
                continue;
            }
            if (exited) {  // on from the exit, outside
                ray = Ray(ray.at(tmax), ray.d);
                medium = medium->exterior();
                continue;
            }
        }

        // ---- escaped: infinite emitters
        if (!found) {
            if (!(cfg.hide_emitters && depth == 0)) {
                for (const Emitter* e : scene_.infinite_emitters()) {
                    Rgb Le = e->eval_direction(ray.d);
                    if (Le.is_black()) continue;
                    float w = hit_weight(e->pdf_direction(ray.d) * sel_pdf);
                    L += throughput() * Le * w;
                }
            }
            break;
        }

        const Shape* shape = hit.shape;
        // ---- emission from an area light
        if (shape->emitter && !(cfg.hide_emitters && depth == 0)) {
            Rgb Le = shape->emitter->eval_surface(hit, -ray.d);
            if (!Le.is_black()) {
                float w = hit_weight(shape->emitter->pdf_surface(prev_p, hit) * sel_pdf);
                L += throughput() * Le * w;
            }
        }

        const Bsdf& bsdf = *shape->bsdf;
        const TexturePoint at = hit.texture_point();
        const float pass = bsdf.transparency(at);
        const bool absent = pass > 0 && sampler.next_1d() < pass;  // a mask's hole (Mitsuba's null lobe)
        if (absent && !vol) {
            // Mitsuba's path: the mask's absence is a Dirac null event and a bounce of the path
            if (cfg.max_depth >= 0 && depth + 1 >= cfg.max_depth) break;
            prev_delta = true;
            prev_p = hit.p;
            ray = Ray(offset_ray_origin(hit.p, hit.ng, ray.d), ray.d);
            ++depth;
            if (!russian_roulette()) break;
            continue;
        }
        if (bsdf.is_null() || absent) {
            // index-matched interface: continue straight, possibly into another medium
            if (++null_crossings > kMaxNullCrossings) break;
            if (vol && shape->is_medium_transition()) medium = shape->target_medium(hit.ng, ray.d);
            ray = Ray(offset_ray_origin(hit.p, hit.ng, ray.d), ray.d);
            continue;
        }

        if (cfg.max_depth >= 0 && depth + 1 >= cfg.max_depth) break;

        // Mitsuba 3's shading frame: tangent = dp/du orthogonalised against the shading normal.
        // Like Mitsuba, directions are judged in this frame only: a direction below the
        // geometric normal but above the shading normal is kept (the BSDF decides).
        Frame frame = Frame::shading(hit.ns, hit.dpdu);
        Vec3 wo_l = frame.to_local(-ray.d);
        if (!bsdf.is_delta() && !emitters.empty()) {
            // shadow rays leave on the side of wi; pick the origin and medium accordingly
            size_t idx = std::min(size_t(sampler.next_1d() * float(emitters.size())), emitters.size() - 1);
            Vec2 u = sampler.next_2d();
            EmitterSample es;
            if (emitters[idx]->sample_li(hit.p, u, &es) && !es.Li.is_black() && es.pdf > 0 && (es.delta || nee_non_delta)) {
                Vec3 wi_l = frame.to_local(es.wi);
                Rgb f = bsdf.eval(at, wo_l, wi_l);
                const float light_pdf = es.pdf * sel_pdf;
                const float w = f.is_black() || es.delta ? 1.0f : nee_weight(light_pdf, bsdf.pdf(at, wo_l, wi_l));
                const float survival = f.is_black() ? 0.0f : shadow_survival(f, w, light_pdf);
                if (survival > 0) {
                    const Medium* m = medium;
                    if (vol && shape->is_medium_transition()) m = shape->target_medium(hit.ng, es.wi);
                    Vec3 o = offset_ray_origin(hit.p, hit.ng, es.wi);
                    float dist = std::isfinite(es.dist) ? length(hit.p + es.wi * es.dist - o) * (1.0f - 1e-4f) : kInf;
                    Rgb T = shadow_transmittance(o, es.wi, dist, vol ? m : nullptr, sampler);
                    if (!T.is_black()) L += throughput() * f * es.Li * T * (w / light_pdf / survival);
                }
            }
        }

        BsdfSample bs;
        if (!bsdf.sample(at, wo_l, sampler.next_1d(), sampler.next_2d(), &bs)) break;
        Vec3 wi = frame.to_world(bs.wi);
        beta *= bs.weight;
        if (beta.is_black() || !beta.finite()) break;
        eta_scale *= bs.eta * bs.eta;
        prev_delta = bs.delta;
        prev_pdf = bs.pdf;
        prev_p = hit.p;
        if (vol && shape->is_medium_transition()) medium = shape->target_medium(hit.ng, wi);
        ray = Ray(offset_ray_origin(hit.p, hit.ng, wi), wi);
        ++depth;
        if (!russian_roulette()) break;
    }
    return L;
}

}  // namespace mf
