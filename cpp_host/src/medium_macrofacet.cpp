// mfhost — the macrofacet medium through the library's tracking API (see medium_macrofacet.h).
#include "medium_macrofacet.h"

#include <macrofacet.h>

#include <cmath>
#include <memory>
#include <cstdio>

#include "library_abi.h"
#include "mean_surface.h"
#include "medium_field.h"
#include "medium_fields.h"
#include "medium_params.h"

namespace mf {
namespace {

mf_frame frame_of(const MediumInteraction& mi) { return mf_frame{to_mf(mi.frame_n), to_mf(mi.frame_t)}; }

/// Slots held by live threads, one bit each (MacrofacetMedium::Tally): 64 leasable slots.
std::atomic<uint64_t> held_tally_slots{0};
constexpr unsigned kLeasableSlots = 64;

/// A thread's lease on a tally slot: the lowest free one, given back when the thread ends (the
/// release orders its counts before the next holder's); kLeasableSlots (the shared slot) when
/// none is free.
struct TallyLease {
    unsigned slot = kLeasableSlots;
    TallyLease() {
        uint64_t taken = held_tally_slots.load(std::memory_order_relaxed);
        while (~taken != 0) {
            const unsigned s = unsigned(__builtin_ctzll(~taken));
            if (held_tally_slots.compare_exchange_weak(taken, taken | uint64_t(1) << s, std::memory_order_acquire,
                                                       std::memory_order_relaxed)) {
                slot = s;
                return;
            }
        }
    }
    ~TallyLease() {
        if (slot < kLeasableSlots) held_tally_slots.fetch_and(~(uint64_t(1) << slot), std::memory_order_release);
    }
};

/// This thread's tally slot, or kLeasableSlots for the shared one. The slot is cached in a
/// trivially initialised thread-local (initial-exec: mfhost is linked into executables), so that
/// the lease's guard and TLS lookup are paid once per thread.
unsigned tally_slot() {
    static thread_local unsigned cached __attribute__((tls_model("initial-exec"))) = ~0u;
    if (cached == ~0u) {
        thread_local const TallyLease lease;
        cached = lease.slot;
    }
    return cached;
}

/// The library's phase function (seeds/000 Eq. 11 with the flakes' reflectance) in the frame the
/// tracker returned with the collision. Host convention: `wo` points back along the incoming ray,
/// `wi` is the new direction; the library's `wi` is our `wo` and its `wo` our `wi`.
class MacrofacetPhaseFn final : public PhaseFunction {
public:
    MacrofacetPhaseFn(const mf_medium* h, std::string label) : h_(h), label_(std::move(label)) {}

    Rgb eval(const MediumInteraction& mi, const Vec3& wo, const Vec3& wi) const override {
        float pdf;
        return eval_pdf(mi, wo, wi, &pdf);
    }
    float pdf(const MediumInteraction& mi, const Vec3& wo, const Vec3& wi) const override {
        float pdf;
        eval_pdf(mi, wo, wi, &pdf);
        return pdf;
    }
    Rgb eval_pdf(const MediumInteraction& mi, const Vec3& wo, const Vec3& wi, float* pdf) const override {
        mf_frame fr = frame_of(mi);
        mf_phase_value v;
        mf_local_params local;
        check(mf_phase_eval_pdf_local(h_, load_local(mi, 0, &local), &fr, to_mf_unit(wo), to_mf_unit(wi), &v), "mf_phase_eval_pdf");
        *pdf = float(v.pdf);
        return Rgb(float(v.value.r), float(v.value.g), float(v.value.b));
    }
    bool sample(const MediumInteraction& mi, const Vec3& wo, Sampler& sampler, Vec3* wi, float* pdf,
                Rgb* weight) const override {
        double u[MF_PHASE_SAMPLE_DIMENSIONS];
        for (double& x : u) x = double(sampler.next_1d());
        mf_frame fr = frame_of(mi);
        mf_phase_sample_result s;
        mf_local_params local;
        check(mf_phase_sample_local(h_, load_local(mi, 0, &local), &fr, to_mf_unit(wo), u, &s), "mf_phase_sample");
        if (!s.valid || !(s.pdf > 0)) return false;
        *wi = from_mf(s.wo);
        *pdf = float(s.pdf);
        *weight = Rgb(float(s.weight.r), float(s.weight.g), float(s.weight.b));
        return weight->finite() && std::isfinite(*pdf);
    }

private:
    void check(mf_status st, const char* what) const {
        if (st != MF_OK) throw Error(label_ + ": " + what + " failed: " + mf_last_error());
    }
    const mf_medium* h_;
    std::string label_;
};

/// `exit_level` 0: up to t_max only; no roulette's survival; `hint` 0: none (mf_track_query).
mf_track_query query(const Ray& ray, float t_max, double exit_level, Sampler& sampler, uint64_t hint = 0) {
    return mf_track_query{to_mf(ray.o), to_mf_unit(ray.d), std::isfinite(t_max) ? double(t_max) : INFINITY, sampler.next_u64(),
                          exit_level, 0.0, hint};
}

}  // namespace

// ----------------------------------------------------------------------------------------------
// MacrofacetMedium

MacrofacetMedium::MacrofacetMedium(mf_medium* handle, std::shared_ptr<const MeanSurface> surface, std::string label,
                                   std::shared_ptr<const LibraryField> field)
    : handle_(handle), surface_(std::move(surface)), field_(std::move(field)), label_(std::move(label)) {
    phase_ = std::make_shared<MacrofacetPhaseFn>(handle_, label_);
    // (Its levels hold for stationary parameters only.)
    if (mf_medium_shell_top(handle_, &top_) != MF_OK ||
        (!field_ && mf_track_opaque_core(handle_, surface_->handle(), &core_start_, &core_level_) != MF_OK)) {
        std::string msg = mf_last_error();
        mf_medium_free(handle_);
        throw Error(label_ + ": " + msg);
    }
}

MacrofacetMedium::~MacrofacetMedium() {
    uint64_t v = violations_.load();
    if (v > 0)
        std::fprintf(stderr, "mfrender: warning: %s: the majorant was exceeded at %llu tentative collisions\n",
                     label_.c_str(), (unsigned long long)v);
    mf_medium_free(handle_);
}

unsigned tally_slots_held() { return unsigned(__builtin_popcountll(held_tally_slots.load())); }

void MacrofacetMedium::count(const mf_track_stats& s) const {
    static_assert(kTallySlots == kLeasableSlots, "one slot per bit of held_tally_slots, and the shared one after them");
    const unsigned slot = tally_slot();
    Tally& t = tallies_[slot];
    auto add = [own = slot < kTallySlots](std::atomic<uint64_t>& to, uint64_t n) {
        if (own)  // this thread's own slot: the only writer
            to.store(to.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);
        else
            to.fetch_add(n, std::memory_order_relaxed);
    };
    add(t.calls, 1);
    add(t.queries, s.surface_queries);
    add(t.segments, s.segments);
    add(t.tentative, s.tentative_collisions);
    if (s.majorant_violations) violations_.fetch_add(s.majorant_violations, std::memory_order_relaxed);
}

TrackCounts MacrofacetMedium::counts() const {
    TrackCounts c;
    for (const Tally& t : tallies_) {
        c.calls += t.calls.load();
        c.surface_queries += t.queries.load();
        c.segments += t.segments.load();
        c.tentative_collisions += t.tentative.load();
    }
    c.majorant_violations = violations_.load();
    return c;
}

void MacrofacetMedium::find_exits(double exit_level, const Medium* exterior, unsigned near_scene) {
    if (!(exit_level >= top_ && std::isfinite(exit_level)))
        throw Error(label_ + ": exit level " + std::to_string(exit_level) + " below the shell's top " + std::to_string(top_));
    exit_level_ = exit_level;
    exterior_ = exterior;
    near_scene_ = near_scene;
    finds_exits_ = true;
}

bool MacrofacetMedium::sample_free_flight(const Ray& ray, float t_max, const MediumInteraction* from, int, Sampler& sampler,
                                          MediumInteraction* mi, Rgb* weight, Rgb* pdf_ratio) const {
    *weight = Rgb(1.0f);  // grey medium: the albedo lives in the phase function
    *pdf_ratio = Rgb(1.0f);
    float t_end;
    return flight(query(ray, t_max, 0.0, sampler, hint_of(from)), ray, mi, &t_end);
}

bool MacrofacetMedium::sample_free_flight_to_exit(const Ray& ray, float t_max, const MediumInteraction* from, Sampler& sampler,
                                                  MediumInteraction* mi, float* t_end) const {
    return flight(query(ray, t_max, exit_level_, sampler, hint_of(from)), ray, mi, t_end);
}

bool MacrofacetMedium::flight(const mf_track_query& q, const Ray& ray, MediumInteraction* mi, float* t_end) const {
    mf_collision c;
    const mf_field* field = field_ ? field_->handle() : nullptr;
    void* user_data = field_ ? field_->user_data() : nullptr;
    if (mf_track_free_flight(handle_, surface_->handle(), field, user_data, &q, &c) != MF_OK)
        throw Error(label_ + ": mf_track_free_flight failed: " + mf_last_error());
    count(c.stats);
    *t_end = float(c.t);
    if (!c.scattered) return false;
    mi->t = float(c.t);
    mi->p = from_mf(c.p);
    mi->wo = -ray.d;
    mi->frame_n = from_mf(c.frame.normal);
    mi->frame_t = from_mf(c.frame.tangent);
    mi->sdf_f = float(c.f);
    mi->surface_hint = c.hint;
    store_local(c.local, mi, 0);
    mi->medium = this;
    return true;
}

Rgb MacrofacetMedium::transmittance(const Ray& ray, float t_max, Sampler& sampler) const {
    float t_end;
    return transmittance_of(query(ray, t_max, 0.0, sampler), &t_end);
}

Rgb MacrofacetMedium::transmittance_kept(const Ray& ray, float t_max, Sampler& sampler, double survival) const {
    mf_track_query q = query(ray, t_max, 0.0, sampler);
    q.survival = survival;
    float t_end;
    return transmittance_of(q, &t_end);
}

double MacrofacetMedium::depth_roulette(double f_from, double f_to, double u) const {
    double survival;
    if (mf_track_depth_roulette(handle_, surface_->handle(), f_from, f_to, u, &survival) != MF_OK)
        throw Error(label_ + ": mf_track_depth_roulette failed: " + mf_last_error());
    return survival;
}

Rgb MacrofacetMedium::transmittance_to_exit(const Ray& ray, float t_max, const MediumInteraction* from, Sampler& sampler,
                                            float* t_end) const {
    return transmittance_of(query(ray, t_max, exit_level_, sampler, hint_of(from)), t_end);
}

Rgb MacrofacetMedium::transmittance_of(const mf_track_query& q, float* t_end) const {
    mf_transmittance t;
    const mf_field* field = field_ ? field_->handle() : nullptr;
    void* user_data = field_ ? field_->user_data() : nullptr;
    if (mf_track_transmittance(handle_, surface_->handle(), field, user_data, &q, &t) != MF_OK)
        throw Error(label_ + ": mf_track_transmittance failed: " + mf_last_error());
    count(t.stats);
    *t_end = float(t.t);
    return Rgb(float(t.transmittance));
}

double MacrofacetMedium::sigma_t_at(const Vec3& p, const Vec3& d, Vec3* normal, Vec3* tangent, float* f) const {
    double fd = surface_->eval(p, normal, tangent);
    *f = float(fd);
    mf_frame fr{to_mf(*normal), to_mf(*tangent)};
    double st = 0;
    if (mf_medium_sigma_t(handle_, &fr, fd, to_mf_unit(d), &st) != MF_OK)
        throw Error(label_ + ": mf_medium_sigma_t failed: " + mf_last_error());
    return st;
}

std::shared_ptr<MacrofacetMedium> create_macrofacet_medium(const MediumParamBag& bag, const Shape& mean, size_t threads) {
    if (bag.type != "macrofacet") throw Error(bag.loc, "not a macrofacet medium");
    // Spatially varying parameters: the base medium takes each at its largest value (its sigma
    // is then the region's), the field gives the local ones (medium_field.h).
    const MediumParamBag base = base_bag(bag);
    ParamsHandle params = bag_to_params(base);
    mf_medium* handle = nullptr;
    if (mf_medium_new(params.get(), &handle) != MF_OK) throw medium_param_error(base, mf_last_error());
    std::unique_ptr<mf_medium, void (*)(mf_medium*)> owned(handle, mf_medium_free);  // freed if the field throws
    std::shared_ptr<const LibraryField> field = library_field_of(bag);
    // The surface is built for this medium's reach, its largest shell top (mf_surface_new_mesh).
    double top = 0;
    if (mf_medium_shell_top(handle, &top) != MF_OK) throw Error(bag.loc, mf_last_error());
    auto surface = MeanSurface::of(mean, threads, top);
    return std::make_shared<MacrofacetMedium>(owned.release(), std::move(surface), medium_label(bag), std::move(field));
}

}  // namespace mf
