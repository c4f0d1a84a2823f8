// mfhost — spatially varying macrofacet/gpis parameters from the scene XML (see medium_fields.h).
#include "medium_fields.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "shape.h"
#include "varying_param.h"

namespace mf {

namespace {

std::string describe(const MediumParamBag& bag) {
    return "<medium type=\"" + bag.type + "\"" + (bag.id.empty() ? std::string() : " id=\"" + bag.id + "\"") + ">";
}

std::string box_str(const Aabb& b) {
    return "[" + number_str(b.lo.x) + ", " + number_str(b.hi.x) + "] x [" + number_str(b.lo.y) + ", " + number_str(b.hi.y) + "] x [" + number_str(b.lo.z) + ", " +
           number_str(b.hi.z) + "]";
}

/// A <volume> element read but not yet checked against a parameter.
struct VolumeSpec {
    const SceneObject* obj = nullptr;
    // constvolume: the `value` property as written (double precision for a float)
    const Property* value = nullptr;
    double default_value = 1.0;  // Mitsuba's constvolume default
    // gridvolume
    std::shared_ptr<const VolumeGridData> data;
    Mat4 to_world;  // unit cube -> world
    VolumeFilter filter = VolumeFilter::Trilinear;
    WrapMode wrap = WrapMode::Clamp;
    std::string path;
    bool constant() const { return data == nullptr; }
    int channels() const {
        if (data) return data->channels;
        return value && value->type == PropType::Rgb ? 3 : 1;
    }
    float component(int c) const {
        if (!value) return float(default_value);
        return value->type == PropType::Rgb ? value->rgb[c] : float(value->f);
    }
};

/// Mitsuba's gridvolume/constvolume parameters (volume.h); throws mf::Error at o's lines.
VolumeSpec parse_volume(const SceneObject& o, VolumeFileCache& files) {
    VolumeSpec v;
    v.obj = &o;
    if (o.type == "constvolume") {
        // a constant has no position; to_world places only its box (Mitsuba's Volume::bbox, the
        // extent of a heterogeneous medium)
        v.to_world = o.get_transform("to_world", Mat4());
        v.value = o.find("value");
        if (v.value) {
            v.value->used = true;
            if (v.value->type != PropType::Float && v.value->type != PropType::Rgb)
                throw Error(v.value->loc, o.describe() + ": parameter \"value\" must be a float or an rgb, got " +
                                              prop_type_name(v.value->type));
        }
        o.check_all_used();
        return v;
    }
    if (o.type != "gridvolume")
        throw Error(o.loc, o.describe() + ": unsupported volume plugin " + quote(o.type) + " (supported: constvolume, gridvolume)");
    const std::string name = o.get_string("filename");
    v.path = o.resolve_path(name);
    if (!is_regular_file(v.path))
        throw Error(o.loc_of("filename"), o.describe() + ": parameter \"filename\" refers to a missing file " + quote(v.path, 200));
    const bool vdb = is_vdb_path(v.path);
    if (o.has("grid") && !vdb)
        throw Error(o.loc_of("grid"), o.describe() + ": parameter \"grid\" names a grid of an OpenVDB (.vdb) file; " +
                                          quote(name, 200) + " is a Mitsuba .vol file");
    const std::string grid_name = vdb ? o.get_string("grid", "") : std::string();
    const std::string ft = o.get_string("filter_type", "trilinear"), wm = o.get_string("wrap_mode", "clamp");
    if (ft == "trilinear") v.filter = VolumeFilter::Trilinear;
    else if (ft == "nearest") v.filter = VolumeFilter::Nearest;
    else throw Error(o.loc_of("filter_type"), o.describe() + ": parameter \"filter_type\" must be trilinear or nearest, got " + quote(ft));
    if (wm == "clamp") v.wrap = WrapMode::Clamp;
    else if (wm == "repeat") v.wrap = WrapMode::Repeat;
    else if (wm == "mirror") v.wrap = WrapMode::Mirror;
    else throw Error(o.loc_of("wrap_mode"), o.describe() + ": parameter \"wrap_mode\" must be clamp, repeat or mirror, got " + quote(wm));
    o.get_bool("raw", false);    // Mitsuba: no spectral upsampling; RGB data is used as given anyway
    o.get_bool("accel", true);   // Mitsuba: GPU texture hardware; no effect on the CPU
    const bool use_grid_bbox = o.get_bool("use_grid_bbox", false);
    if (vdb && o.has("use_grid_bbox"))
        throw Error(o.loc_of("use_grid_bbox"), o.describe() + ": parameter \"use_grid_bbox\" applies to .vol files; a .vdb grid "
                                                              "is always placed by its own transform");
    const Mat4 user = o.get_transform("to_world", Mat4());
    try {
        v.data = files.grid(o, v.path, grid_name, GridCentering::Cell);
    } catch (const Error& e) {
        throw Error(o.loc, o.describe() + ": " + e.what());
    }
    Mat4 placement;  // unit cube -> the grid's own space
    if (v.data->has_grid_to_world) {
        placement = v.data->grid_to_world;
    } else if (use_grid_bbox) {
        const Aabb& b = v.data->bbox;
        placement = Mat4::translate(b.lo.x, b.lo.y, b.lo.z) * Mat4::scale(b.hi.x - b.lo.x, b.hi.y - b.lo.y, b.hi.z - b.lo.z);
    }
    v.to_world = user * placement;
    if (!v.to_world.finite() || std::fabs(v.to_world.det3()) < 1e-30)
        throw Error(o.loc, o.describe() + ": the grid's placement (to_world" + (use_grid_bbox ? std::string(" and the file's bounding box") : "") +
                               ") is singular");
    o.check_all_used();
    return v;
}

std::string voxel_str(const VolumeGridData& g, size_t index) {
    size_t i = index % size_t(g.nx), j = (index / size_t(g.nx)) % size_t(g.ny), k = index / (size_t(g.nx) * size_t(g.ny));
    return "voxel (" + std::to_string(i) + ", " + std::to_string(j) + ", " + std::to_string(k) + ")";
}

Error value_error(const VolumeSpec& v, const std::string& param, const std::string& where, double x, Constraint c) {
    return Error(v.obj->loc, v.obj->describe() + " of parameter " + quote(param) + ": " + where + " is " + number_str(x) + ", but " +
                                 param + " " + constraint_text(c) +
                                 (v.path.empty() ? std::string() : " (file " + quote(v.path, 200) + ")"));
}

/// Checks every sample of a volume against the parameter's constraint.
void check_volume_values(const VolumeSpec& v, const VaryingParam& p) {
    if (v.constant()) {
        for (int c = 0; c < v.channels(); ++c)
            if (!satisfies(p.constraint, v.component(c)))
                throw value_error(v, p.name, "the value" + (v.channels() > 1 ? " (channel " + std::to_string(c) + ")" : std::string()),
                                  v.component(c), p.constraint);
        return;
    }
    const VolumeGridData& g = *v.data;
    for (size_t i = 0; i < g.values.size(); ++i)
        if (!satisfies(p.constraint, g.values[i]))
            throw value_error(v, p.name,
                              voxel_str(g, i / size_t(g.channels)) +
                                  (g.channels > 1 ? " channel " + std::to_string(i % size_t(g.channels)) : std::string()),
                              g.values[i], p.constraint);
}

/// A volume's channel count must fit the parameter: its own count, or 1 (grey) where it takes 3.
void check_channels(const VolumeSpec& v, const VaryingParam& p) {
    const int c = v.channels();
    if (c == p.channels || (p.channels == 3 && c == 1)) return;
    std::string want = p.channels == 1 ? "1 channel (a float)" : (p.channels == 3 ? "1 or 3 channels (float or rgb)" : "6 channels");
    std::string hint = std::string(p.name) == "anisotropy" && v.constant()
                           ? " (a constant matrix: give anisotropy_diagonal and anisotropy_offdiagonal as rgb constvolumes)"
                           : "";
    throw Error(v.obj->loc, v.obj->describe() + " of parameter " + quote(p.name) + " has " + std::to_string(c) +
                                " channel" + (c == 1 ? "" : "s") + ", but " + p.name + " takes " + want + hint);
}

bool same_layout(const VolumeSpec& a, const VolumeSpec& b) {
    if (a.data->nx != b.data->nx || a.data->ny != b.data->ny || a.data->nz != b.data->nz || a.filter != b.filter || a.wrap != b.wrap)
        return false;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (a.to_world.m[i][j] != b.to_world.m[i][j]) return false;
    return true;
}

/// The anisotropy from `full` (6 channels) or from its halves (either may be null; a missing
/// off-diagonal half is zero). Every sample's matrix must be positive definite.
std::shared_ptr<const Field> build_anisotropy(const VolumeSpec* full, const VolumeSpec* diag, const VolumeSpec* off) {
    const VolumeSpec* layout = full ? full : (diag && !diag->constant() ? diag : (off && !off->constant() ? off : nullptr));
    if (diag && off && !diag->constant() && !off->constant() && !same_layout(*diag, *off))
        throw Error(off->obj->loc, off->obj->describe() + " of parameter \"anisotropy_offdiagonal\": its grid must have the layout "
                                                          "of anisotropy_diagonal's (" +
                                       diag->obj->loc.str() + "): the same size, to_world, filter_type and wrap_mode, so that every "
                                                              "voxel's matrix is known");
    const size_t count = layout ? size_t(layout->data->nx) * layout->data->ny * layout->data->nz : 1;
    std::vector<float> samples(count * 8);
    // entry c of sample i from a half (3 channels, or 1 broadcast)
    auto half = [](const VolumeSpec* h, size_t i, int c) -> double {
        if (!h) return 0.0;
        if (h->constant()) return h->component(h->channels() == 3 ? c : 0);
        const VolumeGridData& g = *h->data;
        return g.values[i * size_t(g.channels) + size_t(g.channels == 3 ? c : 0)];
    };
    for (size_t i = 0; i < count; ++i) {
        double s[6];
        for (int c = 0; c < 6; ++c) s[c] = full ? full->data->values[i * 6 + size_t(c)] : half(c < 3 ? diag : off, i, c % 3);
        if (!positive_definite(s)) {
            const VolumeSpec* at = full ? full : (diag && !diag->constant() ? diag : (off && !off->constant() ? off : diag));
            std::string where = layout ? voxel_str(*layout->data, i) : std::string("the matrix");
            throw Error(at->obj->loc, at->obj->describe() + " of parameter " +
                                          quote(full ? "anisotropy" : (at == off ? "anisotropy_offdiagonal" : "anisotropy_diagonal")) +
                                          ": " + where + " is not positive definite: (xx, yy, zz, xy, xz, yz) = (" + number_str(s[0]) + ", " +
                                          number_str(s[1]) + ", " + number_str(s[2]) + ", " + number_str(s[3]) + ", " + number_str(s[4]) + ", " + number_str(s[5]) +
                                          ") (the local anisotropy of seeds/004 Eq. 25 must be a positive-definite matrix)");
        }
        matrix_sample(s, &samples[i * 8]);
    }
    const VolumeSpec& origin = full ? *full : *diag;
    std::shared_ptr<const Volume> vol;
    if (!layout) vol = make_constant_volume(samples.data(), 6, 8);
    else
        vol = make_grid_volume(SampleGrid(std::move(samples), layout->data->nx, layout->data->ny, layout->data->nz, 8), 6,
                               layout->to_world, layout->filter, layout->wrap);
    return std::make_shared<Field>(full ? "anisotropy" : "anisotropy", origin.obj->loc, origin.obj->describe(), vol);
}

/// A grid volume of `channels` (1 or 3) channels: 1-channel data broadcast to 3 where 3 are taken.
std::shared_ptr<const Volume> grid_volume_for(const VolumeSpec& v, int channels) {
    const VolumeGridData& g = *v.data;
    std::vector<float> values;
    if (channels == 3 && g.channels == 1) {
        values.resize(g.values.size() * 3);
        for (size_t i = 0; i < g.values.size(); ++i) values[3 * i] = values[3 * i + 1] = values[3 * i + 2] = g.values[i];
    } else {
        values = g.values;
    }
    return make_grid_volume(SampleGrid(std::move(values), g.nx, g.ny, g.nz, channels), channels, v.to_world, v.filter, v.wrap);
}

/// The bag entry of a constvolume with a scalar form: the `value` property as written.
ParamValue folded_value(const VolumeSpec& v, const VaryingParam& p) {
    ParamValue pv;
    pv.loc = v.obj->loc;
    if (p.channels == 1) {
        pv.kind = ParamValue::Kind::Float;
        pv.f = v.value ? v.value->f : v.default_value;
    } else if (v.value && v.value->type == PropType::Rgb) {
        pv.kind = ParamValue::Kind::Rgb;
        pv.rgb = v.value->rgb;
    } else {
        pv.kind = ParamValue::Kind::Float;  // a grey reflectance: the library takes a float as grey
        pv.f = v.value ? v.value->f : v.default_value;
    }
    return pv;
}

}  // namespace

std::shared_ptr<const VolumeGridData> VolumeFileCache::grid(const SceneObject& o, const std::string& path,
                                                           const std::string& grid_name, GridCentering centering) {
    auto it = grids_.find(&o);
    if (it != grids_.end()) return it->second;
    auto g = std::make_shared<VolumeGridData>(is_vdb_path(path) ? read_vdb_grid(path, grid_name, centering) : read_vol_file(path));
    grids_[&o] = g;
    return g;
}

void check_volume_element(const SceneObject& o, VolumeFileCache& files) {
    VolumeSpec v = parse_volume(o, files);
    if (v.constant()) return;
    for (size_t i = 0; i < v.data->values.size(); ++i)
        if (!std::isfinite(v.data->values[i]))
            throw Error(o.loc, o.describe() + ": " + voxel_str(*v.data, i / size_t(v.data->channels)) + " is not finite (file " +
                                   quote(v.path, 200) + ")");
}

std::shared_ptr<const Volume> build_rgb_volume(const SceneObject& o, VolumeFileCache& files, float max_value, Aabb* world_box) {
    VolumeSpec v = parse_volume(o, files);
    if (v.channels() != 1 && v.channels() != 3)
        throw Error(o.loc, o.describe() + ": has " + std::to_string(v.channels()) + " channels; 1 or 3 are needed here");
    auto bad = [&](const std::string& where, float x) {
        return Error(o.loc, o.describe() + ": " + where + " is " + number_str(x) + ", outside [0, " + number_str(max_value) + "]" +
                                (v.path.empty() ? std::string() : " (file " + quote(v.path, 200) + ")"));
    };
    *world_box = Aabb();
    for (int c = 0; c < 8; ++c) world_box->expand(v.to_world.point(Vec3(float(c & 1), float((c >> 1) & 1), float((c >> 2) & 1))));
    if (v.constant()) {
        float value[3];
        for (int c = 0; c < 3; ++c) {
            value[c] = v.component(v.channels() == 3 ? c : 0);
            if (!(value[c] >= 0 && value[c] <= max_value)) throw bad("the value", value[c]);
        }
        return make_constant_volume(value, 3, 3);
    }
    for (size_t i = 0; i < v.data->values.size(); ++i)
        if (!(v.data->values[i] >= 0 && v.data->values[i] <= max_value))
            throw bad(voxel_str(*v.data, i / size_t(v.data->channels)), v.data->values[i]);
    return grid_volume_for(v, 3);
}

std::shared_ptr<const MediumFields> build_medium_fields(const SceneObject& medium, MediumParamBag* bag, VolumeFileCache& files,
                                                        const TextureBuilder& build_texture) {
    auto fields = std::make_shared<MediumFields>();
    ErrorSink errors;
    std::map<std::string, SourceLoc> seen;
    VolumeSpec full, diag, off;
    bool has_full = false, has_diag = false, has_off = false;
    for (const Child& c : medium.children) {
        const SceneObject& o = *c.obj;
        if (o.tag != "volume" && o.tag != "texture") continue;
        c.used = true;
        try {
            if (o.broken) continue;  // the reader reported it
            const VaryingParam* p = varying_param(c.name);
            if (!p)
                throw Error(c.loc, medium.describe() + ": " + o.describe() +
                                       (c.name.empty() ? std::string(" needs a name=\"...\": the parameter it gives")
                                                       : " names parameter " + quote(c.name) + ", which cannot vary in space") +
                                       " (parameters that can: " + varying_param_list() + ")");
            if (medium.has(c.name))
                throw Error(c.loc, medium.describe() + ": parameter " + quote(c.name) + " is given twice (a value at line " +
                                       std::to_string(medium.loc_of(c.name).line) + " and a " + o.tag + ")");
            if (!seen.emplace(c.name, c.loc).second)
                throw Error(c.loc, medium.describe() + ": parameter " + quote(c.name) + " is given twice (first at line " +
                                       std::to_string(seen[c.name].line) + ")");
            if (o.tag == "texture") {
                if (p->constraint == Constraint::Matrix)
                    throw Error(c.loc, medium.describe() + ": parameter " + quote(c.name) +
                                           " is a matrix in world space: give it as a <volume>, not a texture");
                std::shared_ptr<const Texture> tex = build_texture(o);
                auto field = std::make_shared<Field>(c.name, o.loc, o.describe(), tex, p->channels);
                ValueRange r = field->range();
                for (int ch = 0; ch < field->channels(); ++ch) {
                    bool ok = p->constraint == Constraint::Positive ? r.lo[ch] > 0 : (p->constraint != Constraint::Unit || r.hi[ch] <= 1);
                    if (!ok)
                        throw Error(o.loc, o.describe() + " of parameter " + quote(c.name) + ": its values reach " +
                                               number_str(p->constraint == Constraint::Positive ? r.lo[ch] : r.hi[ch]) + ", but " + c.name +
                                               " " + constraint_text(p->constraint) +
                                               (p->channels == 1 ? " (a scalar is the texture's luminance)" : ""));
                }
                fields->fields.push_back(field);
                continue;
            }
            VolumeSpec v = parse_volume(o, files);
            check_channels(v, *p);
            if (p->constraint == Constraint::Matrix) {
                // Entries may be negative off the diagonal; positive definiteness is checked once
                // the matrix is assembled (build_anisotropy).
                check_volume_values(v, *p);
                if (c.name == "anisotropy") full = v, has_full = true;
                else if (c.name == "anisotropy_diagonal") diag = v, has_diag = true;
                else off = v, has_off = true;
                continue;
            }
            check_volume_values(v, *p);
            if (v.constant()) {
                bag->params.emplace_back(c.name, folded_value(v, *p));
                continue;
            }
            fields->fields.push_back(std::make_shared<Field>(c.name, o.loc, o.describe(), grid_volume_for(v, p->channels)));
        } catch (const Error& e) {
            errors.add(e);
        }
    }
    try {
        if (has_full && (has_diag || has_off))
            throw Error((has_diag ? diag : off).obj->loc,
                        medium.describe() + ": give the anisotropy either as \"anisotropy\" (6 channels) or as its halves "
                                            "\"anisotropy_diagonal\" and \"anisotropy_offdiagonal\", not both");
        if (has_off && !has_diag)
            throw Error(off.obj->loc, medium.describe() + ": \"anisotropy_offdiagonal\" needs \"anisotropy_diagonal\" too");
        if (errors.empty() && (has_full || has_diag))
            fields->fields.push_back(build_anisotropy(has_full ? &full : nullptr, has_diag ? &diag : nullptr, has_off ? &off : nullptr));
    } catch (const Error& e) {
        errors.add(e);
    }
    errors.raise();
    return fields->empty() ? nullptr : fields;
}

double shell_top_bound(const MediumParamBag& bag) {
    auto scalar = [&](const char* name, double* out) {
        const ParamValue* v = bag.get(name);
        if (!v) return false;
        if (v->kind == ParamValue::Kind::Float) *out = v->f;
        else if (v->kind == ParamValue::Kind::Int) *out = double(v->i);
        else return false;
        return true;
    };
    double sigma = 0, x = 0;
    if (scalar("sigma", &x)) sigma = x;
    else if (scalar("variance", &x)) sigma = std::sqrt(std::max(0.0, x));
    if (bag.fields) {
        if (const Field* f = bag.fields->find("sigma")) sigma = std::max(sigma, double(f->range().hi[0]));
        if (const Field* f = bag.fields->find("variance")) sigma = std::max(sigma, std::sqrt(double(f->range().hi[0])));
    }
    double k = bag.type == "gpis" ? 6.0 : 3.0;  // the library's defaults (height.rs, gpis MarchSettings)
    scalar("shell_extent", &k);
    return k * sigma;
}

void check_fields_on_surface(const MediumParamBag& bag, const Shape& shape) {
    if (!bag.fields) return;
    const std::string where = describe(bag);
    const std::string shape_what = "<shape type=\"" + shape.kind() + "\">" + (shape.loc.str().empty() ? "" : " (" + shape.loc.str() + ")");
    if (bag.fields->needs_uv() && !shape.has_uv()) {
        for (const auto& f : bag.fields->fields)
            if (f->domain() == Field::Domain::Texture)
                throw Error(f->loc(), where + ": parameter " + quote(f->param()) + " is a texture over the mean surface's uv, but " +
                                          shape_what + " has no texture coordinates");
    }
    const double top = shell_top_bound(bag);
    Aabb region = shape.bounds();
    const float grow = float(top);
    region.lo -= Vec3(grow);
    region.hi += Vec3(grow);
    for (const auto& f : bag.fields->fields) {
        if (f->domain() != Field::Domain::Volume || f->volume()->covers(region)) continue;
        throw Error(f->loc(), where + ": the grid of parameter " + quote(f->param()) + " does not cover the medium's region " +
                                  box_str(region) + " (the bounding box of " + shape_what + " grown by the shell's top " + number_str(top) +
                                  " = shell_extent x the largest sigma): enlarge the grid or its to_world, or use wrap_mode "
                                  "repeat or mirror");
    }
}

void refuse_varying_fields(const MediumParamBag& bag) {
    if (!bag.fields || bag.fields->empty()) return;
    const Field& f = *bag.fields->fields.front();
    throw Error(f.loc(), describe(bag) + ": parameter " + quote(f.param()) + " varies in space (" + f.element() +
                             "): rendering spatially varying parameters lands with the library's per-query parameter API "
                             "(issue 12); mfrender --check validates such scenes, and a constvolume renders already");
}

}  // namespace mf
