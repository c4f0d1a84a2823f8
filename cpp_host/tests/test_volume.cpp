// Volume data layer tests (issue 12): the .vol reader and writer against hand-built bytes and
// every refusal, OpenVDB grids made dense with their placement, grid-volume evaluation against
// the trilinear / nearest formulas written out here (Mitsuba's cell-centred convention, all wrap
// modes), and the conservative range queries: seeded random segments and boxes whose sampled
// values must all lie inside the returned bounds (the bounds are exact up to float rounding of
// the same arithmetic, so the tolerance is 1e-5 relative), plus the texture ranges.
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <cstring>
#include <random>

#include "check.h"
#include "scene_util.h"
#include "texture.h"
#include "volume.h"
#include "volume_io.h"

using namespace mf;

static VolumeGridData random_grid(int nx, int ny, int nz, int channels, uint32_t seed, float lo = 0.1f, float hi = 2.0f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(lo, hi);
    VolumeGridData g;
    g.nx = nx, g.ny = ny, g.nz = nz, g.channels = channels;
    g.values.resize(size_t(nx) * ny * nz * channels);
    for (float& v : g.values) v = u(rng);
    g.bbox.lo = Vec3(-1, -2, -3);
    g.bbox.hi = Vec3(1, 2, 3);
    return g;
}

// ------------------------------------------------------------------------------- .vol files
TEST_CASE(vol_round_trip_and_layout) {
    VolumeGridData g = random_grid(3, 4, 5, 3, 1);
    write_vol_file(work("rt.vol"), g);
    std::string bytes = read_file(work("rt.vol"));
    // Mitsuba's layout: 48-byte header, then x fastest, channels innermost, little-endian float32
    CHECK(bytes.size() == 48 + 4 * g.values.size());
    CHECK(bytes.compare(0, 3, "VOL") == 0 && bytes[3] == 3);
    int32_t n[5];
    std::memcpy(n, bytes.data() + 4, 20);
    CHECK(n[0] == 1 && n[1] == 3 && n[2] == 4 && n[3] == 5 && n[4] == 3);
    float v;
    std::memcpy(&v, bytes.data() + 48 + 4 * (((2 * 4 + 1) * 3 + 2) * 3 + 1), 4);  // (i, j, k, c) = (2, 1, 2, 1)
    CHECK(v == g.values[((2 * 4 + 1) * 3 + 2) * 3 + 1]);
    VolumeGridData r = read_vol_file(work("rt.vol"));
    CHECK(r.nx == 3 && r.ny == 4 && r.nz == 5 && r.channels == 3);
    CHECK(r.values == g.values);
    CHECK(r.bbox.lo.y == -2 && r.bbox.hi.z == 3);
    CHECK(!r.has_grid_to_world);
}

TEST_CASE(vol_refusals) {
    VolumeGridData g = random_grid(2, 2, 2, 1, 2);
    write_vol_file(work("good.vol"), g);
    const std::string good = read_file(work("good.vol"));
    CHECK_THROWS_WITH(read_vol_file(work("does_not_exist.vol")), "no such file");
    write_file(work("short.vol"), good.substr(0, 20));
    CHECK_THROWS_WITH(read_vol_file(work("short.vol")), "shorter than the 48-byte header");
    // one corrupted byte at a time: `offset` set to `byte`
    auto corrupt = [&](const std::string& name, size_t offset, char byte) {
        std::string bad = good;
        bad[offset] = byte;
        write_file(work(name), bad);
        return read_vol_file(work(name));
    };
    CHECK_THROWS_WITH(corrupt("magic.vol", 0, 'X'), "does not start with \"VOL\"");
    CHECK_THROWS_WITH(corrupt("version.vol", 3, 2), "has version 2: only version 3");
    CHECK_THROWS_WITH(corrupt("encoding.vol", 4, 2), "has encoding 2: only 1 (float32)");
    CHECK_THROWS_WITH(corrupt("channels.vol", 20, 4), "has 4 channels: supported are 1, 3 and 6");
    CHECK_THROWS_WITH(corrupt("size.vol", 8, 0), "non-positive size 0x2x2");
    write_file(work("truncated.vol"), good.substr(0, good.size() - 4));
    CHECK_THROWS_WITH(read_vol_file(work("truncated.vol")), "needs 80: the file is truncated");
    write_file(work("long.vol"), good + "xxxx");
    CHECK_THROWS_WITH(read_vol_file(work("long.vol")), "has 84 bytes, but its header (2x2x2 cells, 1 channels) needs 80");
    std::string bad = good;
    bad[8] = bad[9] = bad[10] = char(0xff);
    bad[11] = 0x7f;  // 2^31 - 1 cells along x
    write_file(work("huge.vol"), bad);
    CHECK_THROWS_WITH(read_vol_file(work("huge.vol")), "more than mfrender loads");
}

// ------------------------------------------------------------------------------- OpenVDB
static void write_vdb(const std::string& path) {
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.25f);
    density->setName("density");
    density->setTransform(openvdb::math::Transform::createLinearTransform(0.5));  // voxel size 0.5
    auto acc = density->getAccessor();
    acc.setValue(openvdb::Coord(1, 2, 3), 2.0f);
    acc.setValue(openvdb::Coord(2, 2, 3), 4.0f);
    auto color = openvdb::Vec3SGrid::create(openvdb::Vec3s(0, 0, 0));
    color->setName("color");
    color->tree().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(0.1f, 0.2f, 0.3f));
    auto ints = openvdb::Int32Grid::create(0);
    ints->setName("labels");
    ints->tree().setValue(openvdb::Coord(0, 0, 0), 7);
    openvdb::GridPtrVec grids{density, color, ints};
    openvdb::io::File(path).write(grids);
}

TEST_CASE(vdb_grids_dense_and_placed) {
    write_vdb(work("tiny.vdb"));
    VolumeGridData d = read_vdb_grid(work("tiny.vdb"), "density", GridCentering::Cell);
    // active box [1,2] x [2,2] x [3,3], padded by one voxel of background: 4 x 3 x 3
    CHECK(d.nx == 4 && d.ny == 3 && d.nz == 3 && d.channels == 1);
    CHECK(d.has_grid_to_world);
    auto at = [&](int i, int j, int k) { return d.values[(size_t(k) * d.ny + j) * d.nx + i]; };
    CHECK(at(1, 1, 1) == 2.0f && at(2, 1, 1) == 4.0f && at(0, 0, 0) == 0.25f && at(3, 2, 2) == 0.25f);
    // the cell centre of sample (1, 1, 1) is VDB index (1, 2, 3), i.e. world (0.5, 1, 1.5)
    Vec3 c = d.grid_to_world.point(Vec3(1.5f / 4, 1.5f / 3, 1.5f / 3));
    CHECK_NEAR(c.x, 0.5, 1e-6);
    CHECK_NEAR(c.y, 1.0, 1e-6);
    CHECK_NEAR(c.z, 1.5, 1e-6);
    // evaluated through a grid volume, the voxel centre gives the voxel's value
    auto vol = make_grid_volume(SampleGrid(d.values, d.nx, d.ny, d.nz, 1), 1, d.grid_to_world, VolumeFilter::Trilinear,
                                WrapMode::Clamp);
    float v;
    vol->eval(Vec3(0.5f, 1.0f, 1.5f), &v);
    CHECK_NEAR(v, 2.0, 1e-5);
    vol->eval(Vec3(0.75f, 1.0f, 1.5f), &v);  // half-way to index (2, 2, 3)
    CHECK_NEAR(v, 3.0, 1e-5);
    // node-centred (sdfgrid): no padding, node i at i / (n - 1)
    CHECK_THROWS_WITH(read_vdb_grid(work("tiny.vdb"), "density", GridCentering::Node),
                      "spans 2x1x1 voxels; an SDF grid needs at least 2 along each axis");
    VolumeGridData col = read_vdb_grid(work("tiny.vdb"), "color", GridCentering::Cell);
    CHECK(col.channels == 3 && col.nx == 3);
    CHECK(col.values[((1 * 3 + 1) * 3 + 1) * 3 + 2] == 0.3f);
    CHECK_THROWS_WITH(read_vdb_grid(work("tiny.vdb"), "sigma", GridCentering::Cell),
                      "has no grid named \"sigma\" (its grids: \"color\", \"density\", \"labels\")");
    CHECK_THROWS_WITH(read_vdb_grid(work("tiny.vdb"), "", GridCentering::Cell), "has 3 grids");
    CHECK_THROWS_WITH(read_vdb_grid(work("tiny.vdb"), "labels", GridCentering::Cell), "has value type \"int32\"");
    CHECK_THROWS_WITH(read_vdb_grid(work("nothere.vdb"), "density", GridCentering::Cell), "no such file");
    write_file(work("garbage.vdb"), "not a vdb file at all");
    CHECK_THROWS_WITH(read_vdb_grid(work("garbage.vdb"), "density", GridCentering::Cell), "cannot read OpenVDB file");
}

// ------------------------------------------------------------------------------- evaluation
/// The reference: Mitsuba's gridvolume written out (u = to_local p; trilinear between cell centres
/// at (i + 0.5) / n; indices wrapped; or nearest: floor(u n)).
static int ref_wrap(long long i, int n, WrapMode m) {
    if (m == WrapMode::Clamp) return int(std::min<long long>(std::max<long long>(i, 0), n - 1));
    long long r = ((i % n) + n) % n;
    if (m == WrapMode::Repeat) return int(r);
    long long period = ((i % (2 * n)) + 2 * n) % (2 * n);
    return int(period < n ? period : 2 * n - 1 - period);
}

static double ref_eval(const VolumeGridData& g, const Mat4& to_world, VolumeFilter f, WrapMode m, const Vec3& p, int c) {
    Mat4 inv = to_world.inverse();
    double u[3];
    for (int a = 0; a < 3; ++a) u[a] = inv.m[a][0] * p.x + inv.m[a][1] * p.y + inv.m[a][2] * p.z + inv.m[a][3];
    const int n[3] = {g.nx, g.ny, g.nz};
    auto sample = [&](long long i, long long j, long long k) {
        return double(g.values[((size_t(ref_wrap(k, n[2], m)) * g.ny + ref_wrap(j, n[1], m)) * g.nx + ref_wrap(i, n[0], m)) * g.channels + c]);
    };
    if (f == VolumeFilter::Nearest)
        return sample((long long)std::floor(u[0] * n[0]), (long long)std::floor(u[1] * n[1]), (long long)std::floor(u[2] * n[2]));
    double x[3], t[3];
    long long i0[3];
    for (int a = 0; a < 3; ++a) {
        x[a] = u[a] * n[a] - 0.5;
        i0[a] = (long long)std::floor(x[a]);
        t[a] = x[a] - double(i0[a]);
    }
    double s = 0;
    for (int corner = 0; corner < 8; ++corner) {
        int d[3] = {corner & 1, (corner >> 1) & 1, (corner >> 2) & 1};
        double w = 1;
        for (int a = 0; a < 3; ++a) w *= d[a] ? t[a] : 1 - t[a];
        s += w * sample(i0[0] + d[0], i0[1] + d[1], i0[2] + d[2]);
    }
    return s;
}

static Mat4 test_to_world() {
    // rotation, non-uniform scale and translation: the grid's box is a general parallelepiped
    return Mat4::translate(0.3, -0.2, 0.1) * Mat4::rotate(1, 2, 3, 30) * Mat4::scale(2.0, 1.5, 1.0);
}

TEST_CASE(eval_matches_trilinear_and_nearest_formulas) {
    VolumeGridData g = random_grid(5, 4, 3, 3, 3);
    const Mat4 tw = test_to_world();
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-2.0f, 2.0f);
    double worst = 0;
    for (VolumeFilter f : {VolumeFilter::Trilinear, VolumeFilter::Nearest})
        for (WrapMode m : {WrapMode::Clamp, WrapMode::Repeat, WrapMode::Mirror}) {
            auto vol = make_grid_volume(SampleGrid(g.values, g.nx, g.ny, g.nz, 3), 3, tw, f, m);
            for (int n = 0; n < 2000; ++n) {
                Vec3 p(u(rng), u(rng), u(rng));  // inside and well outside the grid's box
                float out[3];
                vol->eval(p, out);
                for (int c = 0; c < 3; ++c) {
                    double e = ref_eval(g, tw, f, m, p, c);
                    if (f == VolumeFilter::Nearest && std::fabs(out[c] - e) > 1e-5) {
                        // a point within float rounding of a cell face may read either cell
                        continue;
                    }
                    worst = std::max(worst, std::fabs(out[c] - e));
                }
            }
        }
    CHECK_MSG(worst < 1e-4, "largest difference " + std::to_string(worst));
    // a constant volume returns its value everywhere
    const float k[3] = {0.5f, 0.25f, 2.0f};
    auto cv = make_constant_volume(k, 3, 3);
    float out[3];
    cv->eval(Vec3(100, -5, 3), out);
    CHECK(out[0] == 0.5f && out[1] == 0.25f && out[2] == 2.0f);
    CHECK(cv->constant() && cv->covers(Aabb()));
}

TEST_CASE(nearest_reads_the_cell_under_the_point) {
    // 4 cells along x over [0, 1]: cell i covers [i/4, (i+1)/4)
    VolumeGridData g;
    g.nx = 4, g.ny = g.nz = 1, g.channels = 1;
    g.values = {1, 2, 3, 4};
    auto vol = make_grid_volume(SampleGrid(g.values, 4, 1, 1, 1), 1, Mat4(), VolumeFilter::Nearest, WrapMode::Clamp);
    float v;
    vol->eval(Vec3(0.3f, 0.5f, 0.5f), &v);
    CHECK(v == 2);
    vol->eval(Vec3(0.99f, 0.5f, 0.5f), &v);
    CHECK(v == 4);
    vol->eval(Vec3(-3.0f, 0.5f, 0.5f), &v);  // clamp
    CHECK(v == 1);
    auto tri = make_grid_volume(SampleGrid(g.values, 4, 1, 1, 1), 1, Mat4(), VolumeFilter::Trilinear, WrapMode::Clamp);
    tri->eval(Vec3(0.25f, 0.5f, 0.5f), &v);  // between the centres 0.125 and 0.375
    CHECK_NEAR(v, 1.5, 1e-6);
    tri->eval(Vec3(0.05f, 0.5f, 0.5f), &v);  // before the first centre: clamped to it
    CHECK_NEAR(v, 1.0, 1e-6);
}

// ------------------------------------------------------------------------------- ranges
TEST_CASE(wrap_interval_covers_every_wrapped_index) {
    std::mt19937 rng(5);
    std::uniform_int_distribution<int> lo_d(-40, 40), len_d(0, 30), n_d(1, 9);
    int failures = 0;
    for (int t = 0; t < 3000; ++t) {
        int n = n_d(rng);
        long long lo = lo_d(rng), hi = lo + len_d(rng);
        for (WrapMode m : {WrapMode::Clamp, WrapMode::Repeat, WrapMode::Mirror}) {
            int iv[2][2];
            int count = wrap_interval(lo, hi, n, m, iv);
            std::vector<bool> hit(size_t(n), false), covered(size_t(n), false);
            for (long long i = lo; i <= hi; ++i) hit[size_t(ref_wrap(i, n, m))] = true;
            for (int c = 0; c < count; ++c)
                for (int i = iv[c][0]; i <= iv[c][1]; ++i) covered[size_t(i)] = true;
            for (int i = 0; i < n; ++i)
                if (hit[size_t(i)] != covered[size_t(i)]) ++failures;  // exact: no index more, none less
        }
    }
    CHECK_MSG(failures == 0, std::to_string(failures) + " indices differ");
}

TEST_CASE(pyramid_box_query_contains_brute_force) {
    VolumeGridData g = random_grid(13, 7, 10, 2, 9, -3.0f, 5.0f);
    SampleGrid grid(g.values, g.nx, g.ny, g.nz, 2);
    std::mt19937 rng(6);
    int missed = 0, exact_small = 0, small = 0;
    for (int t = 0; t < 2000; ++t) {
        int lo[3], hi[3];
        const int n[3] = {g.nx, g.ny, g.nz};
        for (int a = 0; a < 3; ++a) {
            std::uniform_int_distribution<int> d(0, n[a] - 1);
            lo[a] = d(rng);
            hi[a] = d(rng);
            if (lo[a] > hi[a]) std::swap(lo[a], hi[a]);
        }
        ValueRange r = ValueRange::empty(2);
        grid.include_range(lo, hi, &r);
        ValueRange brute = ValueRange::empty(2);
        for (int k = lo[2]; k <= hi[2]; ++k)
            for (int j = lo[1]; j <= hi[1]; ++j)
                for (int i = lo[0]; i <= hi[0]; ++i) brute.include(grid.at(i, j, k));
        for (int c = 0; c < 2; ++c)
            if (r.lo[c] > brute.lo[c] || r.hi[c] < brute.hi[c]) ++missed;
        if (hi[0] - lo[0] <= 1 && hi[1] - lo[1] <= 1 && hi[2] - lo[2] <= 1) {
            ++small;  // level 0: the samples themselves
            exact_small += r.lo[0] == brute.lo[0] && r.hi[0] == brute.hi[0];
        }
    }
    CHECK(missed == 0);
    CHECK(small > 0 && exact_small == small);
    ValueRange all = grid.global_range();
    float gmin = kInf, gmax = -kInf;
    for (size_t i = 0; i < g.values.size(); i += 2) gmin = std::min(gmin, g.values[i]), gmax = std::max(gmax, g.values[i]);
    CHECK(all.lo[0] == gmin && all.hi[0] == gmax);
}

TEST_CASE(volume_ranges_contain_sampled_values) {
    VolumeGridData g = random_grid(9, 6, 7, 3, 21, -1.0f, 3.0f);
    const Mat4 tw = test_to_world();
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> u(-2.5f, 2.5f), len(0.0f, 1.0f), u01(0.0f, 1.0f);
    int violations = 0, queries = 0;
    double width_short = 0, width_global = 0;
    for (VolumeFilter f : {VolumeFilter::Trilinear, VolumeFilter::Nearest})
        for (WrapMode m : {WrapMode::Clamp, WrapMode::Repeat, WrapMode::Mirror}) {
            auto vol = make_grid_volume(SampleGrid(g.values, g.nx, g.ny, g.nz, 3), 3, tw, f, m);
            ValueRange global = vol->range();
            for (int t = 0; t < 400; ++t) {
                Vec3 o(u(rng), u(rng), u(rng));
                Vec3 d = normalize(Vec3(u(rng), u(rng), u(rng)));
                // short (a fraction of a cell), medium and long segments
                float L = t % 3 == 0 ? 0.05f * len(rng) : (t % 3 == 1 ? len(rng) : 6.0f * len(rng));
                ValueRange r = vol->range_segment(o, d, L);
                ++queries;
                if (t % 3 == 0) {
                    width_short += r.hi[0] - r.lo[0];
                    width_global += global.hi[0] - global.lo[0];
                }
                for (int s = 0; s <= 64; ++s) {
                    float out[3];
                    vol->eval(o + d * (L * float(s) / 64.0f), out);
                    for (int c = 0; c < 3; ++c) {
                        float tol = 1e-5f * (1.0f + std::fabs(out[c]));
                        if (out[c] < r.lo[c] - tol || out[c] > r.hi[c] + tol) ++violations;
                        if (out[c] < global.lo[c] - tol || out[c] > global.hi[c] + tol) ++violations;
                    }
                }
                Aabb box;
                box.expand(o);
                box.expand(o + Vec3(len(rng), 0.3f * len(rng), 0.7f * len(rng)));
                ValueRange rb = vol->range_box(box);
                for (int s = 0; s < 64; ++s) {
                    Vec3 p = box.lo + Vec3(u01(rng) * box.extent().x, u01(rng) * box.extent().y, u01(rng) * box.extent().z);
                    if (s < 8) p = Vec3((s & 1) ? box.hi.x : box.lo.x, (s & 2) ? box.hi.y : box.lo.y, (s & 4) ? box.hi.z : box.lo.z);
                    float out[3];
                    vol->eval(p, out);
                    for (int c = 0; c < 3; ++c) {
                        float tol = 1e-5f * (1.0f + std::fabs(out[c]));
                        if (out[c] < rb.lo[c] - tol || out[c] > rb.hi[c] + tol) ++violations;
                    }
                }
            }
        }
    CHECK_MSG(violations == 0, std::to_string(violations) + " sampled values outside their bounds in " + std::to_string(queries) + " queries");
    // short segments are bounded locally, not by the whole grid
    CHECK_MSG(width_short < 0.6 * width_global,
              "short-segment bounds " + std::to_string(width_short) + " vs global " + std::to_string(width_global));
    // degenerate inputs fall back to the global range instead of failing
    auto vol = make_grid_volume(SampleGrid(g.values, g.nx, g.ny, g.nz, 3), 3, tw, VolumeFilter::Trilinear, WrapMode::Clamp);
    ValueRange inf_seg = vol->range_segment(Vec3(0.0f), Vec3(1, 0, 0), kInf);
    CHECK(inf_seg.lo[0] == vol->range().lo[0] && inf_seg.hi[0] == vol->range().hi[0]);
}

TEST_CASE(covers_is_the_grid_box_for_clamp) {
    VolumeGridData g = random_grid(4, 4, 4, 1, 4);
    Mat4 tw = Mat4::translate(-1, -1, -1) * Mat4::scale(2, 2, 2);  // [-1, 1]^3
    auto clamp = make_grid_volume(SampleGrid(g.values, 4, 4, 4, 1), 1, tw, VolumeFilter::Trilinear, WrapMode::Clamp);
    auto repeat = make_grid_volume(SampleGrid(g.values, 4, 4, 4, 1), 1, tw, VolumeFilter::Trilinear, WrapMode::Repeat);
    Aabb inside, outside;
    inside.expand(Vec3(-0.9f));
    inside.expand(Vec3(1.0f));
    outside.expand(Vec3(-0.9f));
    outside.expand(Vec3(0.5f, 0.5f, 1.1f));
    CHECK(clamp->covers(inside));
    CHECK(!clamp->covers(outside));
    CHECK(repeat->covers(outside));  // a repeating grid defines every point
}

TEST_CASE(texture_ranges_contain_sampled_values) {
    std::mt19937 rng(31);
    std::uniform_real_distribution<float> u01(0.0f, 1.0f), uv(-1.5f, 2.5f);
    const int w = 7, h = 5;
    std::vector<float> rgb(size_t(w) * h * 3);
    for (float& v : rgb) v = u01(rng);
    UvTransform t = UvTransform::from(Mat4::rotate(0, 0, 1, 20) * Mat4::scale(1.3, 0.8, 1));
    int violations = 0;
    for (BitmapFilter f : {BitmapFilter::Bilinear, BitmapFilter::Nearest})
        for (WrapMode m : {WrapMode::Repeat, WrapMode::Mirror, WrapMode::Clamp}) {
            auto tex = make_bitmap_texture(rgb, w, h, f, m, t);
            ValueRange global = tex->range();
            for (int q = 0; q < 300; ++q) {
                Vec2 lo(uv(rng), uv(rng)), size(0.3f * u01(rng), 0.3f * u01(rng));
                Vec2 hi(lo.x + size.x, lo.y + size.y);
                ValueRange r = tex->range_uv(lo, hi);
                for (int s = 0; s < 32; ++s) {
                    Rgb v = tex->eval(Vec2(lo.x + u01(rng) * size.x, lo.y + u01(rng) * size.y));
                    for (int c = 0; c < 3; ++c) {
                        if (v[c] < r.lo[c] - 1e-6f || v[c] > r.hi[c] + 1e-6f) ++violations;
                        if (v[c] < global.lo[c] - 1e-6f || v[c] > global.hi[c] + 1e-6f) ++violations;
                    }
                }
            }
        }
    CHECK(violations == 0);
    auto c0 = make_constant_texture(Rgb(0.2f, 0.4f, 0.6f)), c1 = make_constant_texture(Rgb(0.9f, 0.1f, 0.5f));
    auto checker = make_checkerboard_texture(c0, c1, UvTransform());
    ValueRange r = checker->range();
    CHECK(r.lo[0] == 0.2f && r.hi[0] == 0.9f && r.lo[1] == 0.1f && r.hi[1] == 0.4f);
    CHECK(checker->max_value() == 0.9f);
}

TEST_MAIN()
