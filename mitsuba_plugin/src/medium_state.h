// macrofacet for Mitsuba 3 — what the medium and its phase function share: the library's
// medium, mean surface and field of spatially varying parameters, the recent collisions, and
// counters for reports.
//
// Events. The phase function of a macrofacet medium depends on the local frame of the mean
// surface at the event (normal = gradient of f, tangent = dp/du; README "Conventions") and, when
// parameters vary in space, on their local values there. Mitsuba hands a phase function only the
// MediumInteraction (p, wi, and sh_frame = Frame(wi), which is not that frame). The tracker
// returns the frame and the local parameters with each collision; the medium remembers the last
// few per thread by position, and the phase function looks its event up there (a shadow ray
// traced between the collision and the phase query may add its own). An event not found there
// (a call from outside volpath's sequence) gets its frame from mf_surface_eval in a stationary
// medium; with a field its local parameters are unknown, and it is counted as unprepared.
// Directions: Mitsuba's mi.wi points away from the event toward where the ray came from, and a
// phase function's wo points away from the event — the library's convention exactly.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <sstream>
#include <string>

#include "cpp_host/src/medium_field.h"
#include "mean_surface.h"

namespace mfmi {

/// Frees an mf_medium (also when a constructor that took it throws).
struct MediumDeleter {
    void operator()(mf_medium* m) const { mf_medium_free(m); }
};

/// The last collisions on this thread (MediumState::event_at).
struct RecentEvents {
    static constexpr int kSize = 4;
    struct Entry {
        uint64_t state_id = 0;
        float p[3] = {0, 0, 0};
        mf_frame frame{};
        mf_local_params local{};
    } entries[kSize];
    int next = 0;
};
inline thread_local RecentEvents t_recent_events;

/// The medium's spatially varying parameters: mfrender's fields and the library field over them
/// (which reads them: declared first, they outlive it).
struct VaryingField {
    std::shared_ptr<const ::mf::MediumFields> fields;
    std::shared_ptr<const ::mf::LibraryField> library;
};

struct MediumState {
    /// Takes ownership of `medium`.
    MediumState(mf_medium* medium, std::shared_ptr<const MeanSurface> surface, VaryingField field, bool diffuse_flakes,
                std::string label, uint64_t seed_salt)
        : owned_(medium), medium(medium), surface(std::move(surface)), field(std::move(field)), diffuse_flakes(diffuse_flakes),
          label(std::move(label)), seed_salt(seed_salt), id(next_id()) {}
    MediumState(const MediumState&) = delete;
    MediumState& operator=(const MediumState&) = delete;

private:
    std::unique_ptr<mf_medium, MediumDeleter> owned_;

public:
    const mf_medium* const medium;
    const std::shared_ptr<const MeanSurface> surface;
    /// Empty for a stationary medium.
    const VaryingField field;
    /// Diffuse flakes need all MF_PHASE_SAMPLE_DIMENSIONS numbers to sample; conductors three.
    const bool diffuse_flakes;
    const std::string label;
    /// Mixed into every tracking seed (a hash of the medium's id in the scene).
    const uint64_t seed_salt;
    /// Unique in the process (a freed state's address may be reused: the thread-local records
    /// must not take a new medium's entries for an old one's).
    const uint64_t id;

    /// The library field for the tracking calls (null for a stationary medium).
    const mf_field* field_handle() const { return field.library ? field.library->handle() : nullptr; }
    void* field_user_data() const { return field.library ? field.library->user_data() : nullptr; }

    /// Remembers a collision at p (Mitsuba's float position of the event).
    void remember(const float p[3], const mf_frame& frame, const mf_local_params& local) const {
        RecentEvents& r = t_recent_events;
        RecentEvents::Entry& e = r.entries[r.next];
        r.next = (r.next + 1) % RecentEvents::kSize;
        e.state_id = id;
        e.p[0] = p[0];
        e.p[1] = p[1];
        e.p[2] = p[2];
        e.frame = frame;
        e.local = local;
    }

    /// The local frame and parameters at p (see the file comment); false for an event whose local
    /// parameters are unknown.
    bool event_at(const float p[3], mf_frame* frame, mf_local_params* local) const {
        for (const RecentEvents::Entry& e : t_recent_events.entries)
            if (e.state_id == id && e.p[0] == p[0] && e.p[1] == p[1] && e.p[2] == p[2]) {
                *frame = e.frame;
                *local = e.local;
                return true;
            }
        if (field.library) {
            unprepared.fetch_add(1, std::memory_order_relaxed);
            return false;
        }
        frame_queries.fetch_add(1, std::memory_order_relaxed);
        const mf_surface_point s = surface->point(mf_vec3{p[0], p[1], p[2]});
        *frame = mf_frame{s.normal, s.tangent};
        *local = mf_local_params{};
        return true;
    }

    // Counters, relaxed atomics read by report(): tracked segments, collisions, the tracker's
    // own counts (mf_track_stats), frames recomputed, call sequences the medium did not prepare,
    // and queries the library refused.
    mutable std::atomic<uint64_t> segments{0}, collisions{0}, surface_queries{0}, tentative{0}, violations{0},
        frame_queries{0}, unprepared{0}, errors{0};

    void count(const mf_track_stats& s, bool scattered) const {
        segments.fetch_add(1, std::memory_order_relaxed);
        if (scattered) collisions.fetch_add(1, std::memory_order_relaxed);
        surface_queries.fetch_add(s.surface_queries, std::memory_order_relaxed);
        tentative.fetch_add(s.tentative_collisions, std::memory_order_relaxed);
        if (s.majorant_violations) violations.fetch_add(s.majorant_violations, std::memory_order_relaxed);
    }

    std::string report() const {
        std::ostringstream os;
        os << "segments = " << segments.load() << ", collisions = " << collisions.load()
           << ", surface_queries = " << surface_queries.load() << ", tentative_collisions = " << tentative.load()
           << ", majorant_violations = " << violations.load() << ", frame_queries = " << frame_queries.load()
           << ", unprepared_calls = " << unprepared.load() << ", errors = " << errors.load();
        if (field.fields)
            for (const auto& f : field.fields->fields) os << ", field " << f->param() << " = " << f->element();
        return os.str();
    }

private:
    static uint64_t next_id() {
        static std::atomic<uint64_t> counter{0};
        return ++counter;
    }
};

}  // namespace mfmi
