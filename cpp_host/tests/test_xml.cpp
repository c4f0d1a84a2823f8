// XML loader tests: defaults/substitution, -D overrides, refs, transform composition against
// hand-computed matrices, error messages naming element + file:line, the macrofacet bag.
// Tolerances: transform entries are compared to 1e-9 (double arithmetic of exact inputs such
// as cos 90° = 6e-17), vector components to 1e-6 (float storage).
#include <memory>

#include "check.h"
#include "scene_builder.h"
#include "xml_scene.h"

using namespace mf;

static const char* kSensor = R"(
  <sensor type="perspective"><float name="fov" value="45"/>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
)";

static ParsedScene parse(const std::string& body, const Defines& d = {}) {
    return parse_scene_string("<scene version=\"3.0.0\">\n" + body + "\n</scene>\n", "mem.xml", d);
}

static const Property* prop(const SceneObject& o, const std::string& name) {
    for (const Property& p : o.props)
        if (p.name == name) return &p;
    return nullptr;
}

TEST_CASE(defaults_and_substitution) {
    const std::string body = R"(<default name="rough" value="0.25"/>
<default name="mat" value="Au"/>
<bsdf type="roughconductor" id="b$mat"><float name="alpha" value="$rough"/><string name="material" value="$mat"/></bsdf>)";
    ParsedScene s = parse(body);
    CHECK(s.root->children.size() == 1);
    const SceneObject& b = *s.root->children[0].obj;
    CHECK(b.id == "bAu");
    CHECK_NEAR(prop(b, "alpha")->f, 0.25, 0);
    CHECK(prop(b, "material")->s == "Au");
    // -D overrides the default; an undeclared -D is harmless
    ParsedScene s2 = parse(body, {{"rough", "0.5"}, {"unused", "1"}});
    CHECK_NEAR(prop(*s2.root->children[0].obj, "alpha")->f, 0.5, 0);
    // substitution inside a longer value
    ParsedScene s3 = parse(R"(<default name="x" value="2"/><bsdf type="diffuse"><rgb name="reflectance" value="0.$x, 0.$x 0.1"/></bsdf>)");
    const Property* r = prop(*s3.root->children[0].obj, "reflectance");
    CHECK_NEAR(r->rgb.r, 0.2, 1e-6);
    CHECK_NEAR(r->rgb.b, 0.1, 1e-6);
}

TEST_CASE(references) {
    ParsedScene s = parse(R"(<bsdf type="diffuse" id="white"/>
<medium type="homogeneous" id="fog"/>
<shape type="sphere" id="ball"><ref id="white"/><ref name="interior" id="fog"/></shape>)");
    CHECK(s.root->children.size() == 3);
    const SceneObject& shape = *s.root->children[2].obj;
    CHECK(shape.children.size() == 2);
    CHECK(shape.children[0].obj == s.root->children[0].obj);  // same object, not a copy
    CHECK(shape.children[1].name == "interior");
    CHECK(shape.children[1].obj->type == "homogeneous");
}

static bool mat_eq(const Mat4& a, const double (&e)[4][4], double tol) {
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (std::fabs(a.m[i][j] - e[i][j]) > tol) return false;
    return true;
}

TEST_CASE(transform_composition) {
    // translate(1,0,0), then rotate 90° about y, then scale 2: M = S * R * T.
    // R_y(90) maps x -> -z and z -> x; so M = [[0,0,2,0],[0,2,0,0],[-2,0,0,-2],[0,0,0,1]].
    ParsedScene s = parse(R"(<shape type="sphere"><transform name="to_world">
        <translate x="1"/><rotate y="1" angle="90"/><scale value="2"/></transform></shape>)");
    Mat4 m = prop(*s.root->children[0].obj, "to_world")->m;
    const double e1[4][4] = {{0, 0, 2, 0}, {0, 2, 0, 0}, {-2, 0, 0, -2}, {0, 0, 0, 1}};
    CHECK(mat_eq(m, e1, 1e-9));
    Vec3 p = m.point(Vec3(0, 0, 0));
    CHECK_NEAR(p.z, -2, 1e-6);

    // lookat origin (0,0,5) -> target 0, up +y: columns left=(-1,0,0), up=(0,1,0), dir=(0,0,-1), origin.
    ParsedScene s2 = parse(R"(<shape type="sphere"><transform name="to_world">
        <lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform></shape>)");
    const double e2[4][4] = {{-1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, -1, 5}, {0, 0, 0, 1}};
    CHECK(mat_eq(prop(*s2.root->children[0].obj, "to_world")->m, e2, 1e-9));

    // matrix (row-major) followed by a non-uniform scale and a rotate about z with x/y/z attributes
    ParsedScene s3 = parse(R"(<shape type="sphere"><transform name="to_world">
        <matrix value="1 0 0 3  0 1 0 4  0 0 1 5  0 0 0 1"/><scale x="2" y="3" z="4"/>
        <rotate z="1" angle="180"/></transform></shape>)");
    // Rz(180) * diag(2,3,4) * T(3,4,5) = [[-2,0,0,-6],[0,-3,0,-12],[0,0,4,20],[0,0,0,1]]
    const double e3[4][4] = {{-2, 0, 0, -6}, {0, -3, 0, -12}, {0, 0, 4, 20}, {0, 0, 0, 1}};
    CHECK(mat_eq(prop(*s3.root->children[0].obj, "to_world")->m, e3, 1e-9));

    // rotate with value="axis" equals rotate with x/y/z; 120° about (1,1,1) permutes the axes x->y->z
    ParsedScene s4 = parse(R"(<shape type="sphere"><transform name="to_world">
        <rotate value="0.57735026919, 0.57735026919, 0.57735026919" angle="120"/></transform></shape>)");
    Vec3 q = prop(*s4.root->children[0].obj, "to_world")->m.vector(Vec3(1, 0, 0));
    CHECK_NEAR(q.x, 0, 1e-6);
    CHECK_NEAR(q.y, 1, 1e-6);
    CHECK_NEAR(q.z, 0, 1e-6);
}

TEST_CASE(property_types) {
    ParsedScene s = parse(R"(<shape type="sphere">
      <integer name="i" value="-3"/><boolean name="b" value="TRUE"/><string name="s" value="hi there"/>
      <vector name="v" x="1" z="3"/><point name="p" value="4, 5 6"/><spectrum name="sp" value="0.4"/>
      <rgb name="c" value="0.5"/></shape>)");
    const SceneObject& o = *s.root->children[0].obj;
    CHECK(prop(o, "i")->i == -3);
    CHECK(prop(o, "b")->b);
    CHECK(prop(o, "s")->s == "hi there");
    CHECK_NEAR(prop(o, "v")->v.y, 0, 0);
    CHECK_NEAR(prop(o, "v")->v.z, 3, 0);
    CHECK_NEAR(prop(o, "p")->v.z, 6, 0);
    CHECK(prop(o, "sp")->type == PropType::Rgb);
    CHECK_NEAR(prop(o, "sp")->rgb.g, 0.4, 1e-7);
    CHECK_NEAR(prop(o, "c")->rgb.b, 0.5, 0);
}

TEST_CASE(parse_errors_name_element_and_line) {
    CHECK_THROWS_WITH(parse("<shape type=\"sphere\">\n<flot name=\"x\" value=\"1\"/></shape>"), "mem.xml:3: unknown element <flot>");
    CHECK_THROWS_WITH(parse("<shape type=\"sphere\">\n\n<float name=\"x\" value=\"1\"></shape>"), "mem.xml:4: malformed XML");
    CHECK_THROWS_WITH(parse("<bsdf type=\"diffuse\">\n<float name=\"a\" value=\"1\"/>\n<float name=\"a\" value=\"2\"/></bsdf>"),
                      "mem.xml:4: <bsdf type=\"diffuse\">: parameter \"a\" was specified more than once");
    CHECK_THROWS_WITH(parse("<bsdf type=\"diffuse\">\n<float name=\"a\" value=\"$nope\"/></bsdf>"), "mem.xml:3: <float>: undefined parameter \"$nope\"");
    CHECK_THROWS_WITH(parse("<shape type=\"sphere\">\n<ref id=\"ghost\"/></shape>"), "mem.xml:3: <ref id=\"ghost\">: no object with this id");
    CHECK_THROWS_WITH(parse("<bsdf type=\"diffuse\">\n<float name=\"a\" value=\"1.5x\"/></bsdf>"), "mem.xml:3: <float>: could not parse number");
    CHECK_THROWS_WITH(parse("<bsdf type=\"diffuse\">\n<integer name=\"a\" value=\"1.5\"/></bsdf>"), "mem.xml:3: <integer name=\"a\">: could not parse integer");
    CHECK_THROWS_WITH(parse("<bsdf type=\"diffuse\">\n<boolean name=\"a\" value=\"yes\"/></bsdf>"), "could not parse boolean");
    CHECK_THROWS_WITH(parse("<bsdf type=\"diffuse\" colour=\"red\"/>"), "mem.xml:2: <bsdf>: unexpected attribute \"colour\"");
    CHECK_THROWS_WITH(parse("<bsdf type=\"diffuse\" id=\"a\"/>\n<bsdf type=\"diffuse\" id=\"a\"/>"), "mem.xml:3: duplicate id \"a\"");
    CHECK_THROWS_WITH(parse("<shape type=\"sphere\"><transform name=\"to_world\">\n<shear/></transform></shape>"),
                      "mem.xml:3: <transform>: unknown transform operation <shear>");
    CHECK_THROWS_WITH(parse("<shape type=\"sphere\"><transform name=\"to_world\">\n<matrix value=\"1 2 3\"/></transform></shape>"),
                      "mem.xml:3: <matrix>: expected 16");
    CHECK_THROWS_WITH(parse_scene_string("<scene version=\"4.0.0\"/>", "v.xml", {}), "v.xml:1: unsupported scene version");
    CHECK_THROWS_WITH(parse_scene_string("<scene/>", "v.xml", {}), "missing the \"version\" attribute");
    CHECK_THROWS_WITH(parse("<include filename=\"/nonexistent/x.xml\"/>"), "mem.xml:2: <include>: no such file");
}

static std::unique_ptr<Scene> build(const std::string& body, bool placeholders = false, BuildReport* rep = nullptr) {
    ParsedScene s = parse(std::string(kSensor) + body);
    BuildOptions o;
    o.allow_macrofacet_placeholders = placeholders;
    return build_scene(s, o, rep);
}

TEST_CASE(builder_errors) {
    CHECK_THROWS_WITH(build("<shape type=\"sphere\">\n<bsdf type=\"diffuse\">\n<rgb name=\"reflectanc\" value=\"0.5\"/></bsdf></shape>"),
                      "mem.xml:7: <bsdf type=\"diffuse\">: unknown parameter \"reflectanc\"");
    CHECK_THROWS_WITH(build("<shape type=\"sphere\">\n<bsdf type=\"roughconductor\">\n<float name=\"alpha\" value=\"-0.1\"/></bsdf></shape>"),
                      "mem.xml:7: <bsdf type=\"roughconductor\">: parameter \"alpha\" must be a non-negative roughness");
    CHECK_THROWS_WITH(build("<shape type=\"sphere\">\n<bsdf type=\"diffuse\">\n<string name=\"reflectance\" value=\"red\"/></bsdf></shape>"),
                      "parameter \"reflectance\" has type string, expected rgb");
    CHECK_THROWS_WITH(build("\n<shape type=\"torus\"/>"), "mem.xml:6: <shape type=\"torus\">: unsupported shape plugin");
    CHECK_THROWS_WITH(build("\n<emitter type=\"sunsky\"/>"), "mem.xml:6: <emitter type=\"sunsky\">: unsupported emitter plugin");
    CHECK_THROWS_WITH(build("\n<shape type=\"rectangle\"><emitter type=\"area\"><texture name=\"radiance\" type=\"checkerboard\"/></emitter></shape>"),
                      "parameter \"radiance\" as a texture is not supported");
    CHECK_THROWS_WITH(build("\n<shape type=\"obj\"><string name=\"filename\" value=\"nope.obj\"/></shape>"),
                      "parameter \"filename\" refers to a missing file");
    CHECK_THROWS_WITH(build("\n<shape type=\"sphere\"><medium type=\"homogeneous\"/></shape>"),
                      "needs name=\"interior\" or name=\"exterior\"");
    CHECK_THROWS_WITH(build("\n<shape type=\"sphere\"><bsdf type=\"dielectric\"><string name=\"int_ior\" value=\"kryptonite\"/></bsdf></shape>"),
                      "names an unknown material \"kryptonite\"");
    CHECK_THROWS_WITH(build("\n<shape type=\"sphere\"><bsdf type=\"conductor\"><string name=\"material\" value=\"Au\"/><rgb name=\"eta\" value=\"1\"/></bsdf></shape>"),
                      "either material or eta/k");
    CHECK_THROWS_WITH(build("\n<integrator type=\"bdpt\"/>"), "unsupported integrator plugin \"bdpt\"");
    CHECK_THROWS_WITH(parse_scene_string("<scene version=\"3.0.0\"><shape type=\"sphere\"/></scene>", "n.xml", {});
                      build_scene(parse_scene_string("<scene version=\"3.0.0\"><shape type=\"sphere\"/></scene>", "n.xml", {}), BuildOptions(), nullptr),
                      "the scene has no <sensor>");
    // good scene builds
    auto sc = build(R"(<bsdf type="dielectric" id="g"><string name="int_ior" value="water"/><float name="ext_ior" value="1"/></bsdf>
      <shape type="cube"><ref id="g"/></shape><emitter type="constant"/>)");
    CHECK(sc->shapes().size() == 1);
    CHECK(sc->emitters().size() == 1);
}

TEST_CASE(macrofacet_parameter_bag) {
    const std::string body = R"(<medium type="macrofacet" id="mf">
        <float name="sigma" value="0.01"/><rgb name="albedo" value="0.9, 0.8, 0.7"/>
        <string name="ndf" value="ggx"/><integer name="k" value="4"/><boolean name="correlated" value="true"/>
      </medium>
      <shape type="sphere" id="ball"><bsdf type="null"/><ref name="interior" id="mf"/></shape>)";
    BuildReport rep;
    auto sc = build(body, true, &rep);
    CHECK(rep.macrofacet.size() == 1);
    if (rep.macrofacet.size() == 1) {
        const auto& u = rep.macrofacet[0];
        CHECK(u.role == "interior");
        CHECK(u.shape->id == "ball");
        CHECK(u.shape->interior_bag == u.bag);
        CHECK(u.bag->type == "macrofacet");
        CHECK(u.bag->params.size() == 5);
        CHECK(u.bag->get("sigma") && u.bag->get("sigma")->kind == ParamValue::Kind::Float && u.bag->get("sigma")->f == 0.01);
        CHECK(u.bag->get("albedo") && u.bag->get("albedo")->kind == ParamValue::Kind::Rgb);
        CHECK(u.bag->get("ndf") && u.bag->get("ndf")->s == "ggx");
        CHECK(u.bag->get("k") && u.bag->get("k")->i == 4);
        CHECK(u.bag->get("correlated") && u.bag->get("correlated")->b);
        CHECK(u.bag->get("sigma")->loc.line == 6);  // body starts on line 5
    }
    // Without placeholders the scene builder hands the bag to the library; the first entry it
    // cannot take is reported at its own line (a boolean here; test_macrofacet covers the rest).
    CHECK_THROWS_WITH(build(body), "mem.xml:7: <medium type=\"macrofacet\" id=\"mf\">: parameter \"correlated\" is a boolean");
    CHECK_THROWS_WITH(build("<medium type=\"macrofacet\" id=\"mf\">\n<float name=\"sigma\" value=\"0.01\"/>\n<float name=\"alpha\" value=\"0.3\"/>\n"
                            "<string name=\"ndf\" value=\"ggx\"/></medium><shape type=\"sphere\"><ref name=\"interior\" id=\"mf\"/></shape>"),
                      "mem.xml:8: <medium type=\"macrofacet\" id=\"mf\">: unknown parameter \"ndf\"");
    // gpis is accepted too; vectors cannot go into a bag
    CHECK_THROWS_WITH(build("<shape type=\"sphere\"><medium type=\"gpis\" name=\"interior\">\n<vector name=\"v\" value=\"1 2 3\"/></medium></shape>", true),
                      "mem.xml:6: <medium type=\"gpis\">: parameter \"v\" has type vector");
}

TEST_CASE(include_files) {
    // <include> splices the included scene's children in place; defaults declared before the
    // include are visible inside it; errors inside report the included file's own lines.
    const std::string dir = MFHOST_TEST_WORK;
    {
        FILE* f = std::fopen((dir + "/inc_part.xml").c_str(), "w");
        std::fputs("<scene version=\"3.0.0\">\n  <bsdf type=\"diffuse\" id=\"fromInclude\"><rgb name=\"reflectance\" value=\"$refl\"/></bsdf>\n</scene>\n", f);
        std::fclose(f);
        f = std::fopen((dir + "/inc_bad.xml").c_str(), "w");
        std::fputs("<scene version=\"3.0.0\">\n\n  <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"$missing\"/></bsdf>\n</scene>\n", f);
        std::fclose(f);
    }
    ParsedScene s = parse_scene_string("<scene version=\"3.0.0\"><default name=\"refl\" value=\"0.3\"/>"
                                       "<include filename=\"inc_part.xml\"/><shape type=\"sphere\"><ref id=\"fromInclude\"/></shape></scene>",
                                       dir + "/main.xml", {});
    CHECK(s.root->children.size() == 2);
    CHECK(s.root->children[1].obj->children[0].obj->id == "fromInclude");
    CHECK_NEAR(prop(*s.root->children[0].obj, "reflectance")->rgb.g, 0.3, 1e-6);
    CHECK_THROWS_WITH(parse_scene_string("<scene version=\"3.0.0\"><include filename=\"inc_bad.xml\"/></scene>", dir + "/main.xml", {}),
                      "inc_bad.xml:3: <rgb>: undefined parameter \"$missing\"");
}

TEST_CASE(reader_limits) {
    // issue 9 item 9: 30,000 nested elements are refused cleanly (no stack overflow)
    std::string deep;
    for (int i = 0; i < 30000; ++i) deep += "<shape type=\"sphere\">";
    for (int i = 0; i < 30000; ++i) deep += "</shape>";
    CHECK_THROWS_WITH(parse(deep), "nested more than 64 deep");
    std::string bsdfs;
    for (int i = 0; i < 30000; ++i) bsdfs += "<bsdf type=\"twosided\">";
    for (int i = 0; i < 30000; ++i) bsdfs += "</bsdf>";
    CHECK_THROWS_WITH(parse(bsdfs), "nested more than 64 deep");
    // a reference chain deeper than the limit, and a cycle
    std::string chain = "<bsdf type=\"diffuse\" id=\"b0\"/>";
    for (int i = 1; i < 100; ++i)
        chain += "<bsdf type=\"twosided\" id=\"b" + std::to_string(i) + "\"><ref id=\"b" + std::to_string(i - 1) + "\"/></bsdf>";
    CHECK_THROWS_WITH(parse(chain), "through references) more than 64 deep");
    CHECK_THROWS_WITH(parse("<bsdf type=\"twosided\" id=\"a\"><ref id=\"a\"/></bsdf>"), "reference cycle");
    // issue 9 item 11: devices are not read; huge values are not echoed whole
    CHECK_THROWS_WITH(parse("<include filename=\"/dev/zero\"/>"), "is not a regular file");
    std::string huge(10 << 20, 'x');
    try {
        parse("<bsdf type=\"diffuse\"><float name=\"a\" value=\"" + huge + "\"/></bsdf>");
        CHECK(false);
    } catch (const Error& e) {
        CHECK(std::string(e.what()).size() < 400);
        CHECK(std::string(e.what()).find("10485760 bytes") != std::string::npos);
    }
    // exponential $substitution is bounded
    std::string defs = "<default name=\"d0\" value=\"xxxxxxxxxxxxxxxx\"/>";
    for (int i = 1; i < 40; ++i)
        defs += "<default name=\"d" + std::to_string(i) + "\" value=\"$d" + std::to_string(i - 1) + "$d" + std::to_string(i - 1) + "\"/>";
    CHECK_THROWS_WITH(parse(defs), "bytes after substituting");
}

TEST_CASE(every_problem_in_one_run) {
    ErrorSink sink;
    ParsedScene s = parse_scene_string("<scene version=\"3.0.0\">\n<shape type=\"sphere\"><float name=\"radius\" value=\"1x\"/></shape>\n"
                                       "<shape type=\"cube\"><float name=\"raduis\" value=\"1\"/><float name=\"foo\" value=\"1\"/></shape>\n"
                                       "<bsdf type=\"plastik\"/>\n<shape type=\"sphere\"><ref id=\"nowhere\"/></shape>\n"
                                       "<sensor type=\"perspective\"/></scene>", "m.xml", {}, &sink);
    build_scene(s, BuildOptions(), nullptr, &sink);
    try {
        sink.raise();
        CHECK(false);
    } catch (const ErrorList& list) {
        CHECK(list.errors().size() == 5);
        std::string all = list.what();
        CHECK(all.find("m.xml:2: <float>: could not parse number") != std::string::npos);
        CHECK(all.find("m.xml:3: <shape type=\"cube\">: unknown parameter \"raduis\"") != std::string::npos);
        CHECK(all.find("m.xml:3: <shape type=\"cube\">: unknown parameter \"foo\"") != std::string::npos);
        CHECK(all.find("m.xml:4: <bsdf type=\"plastik\">: unsupported BSDF plugin") != std::string::npos);
        CHECK(all.find("m.xml:5: <ref id=\"nowhere\">") != std::string::npos);
    }
}

TEST_CASE(mitsuba_scene_conventions) {
    // forward references, aliases, a top-level area emitter used by a shape
    auto sc = build(R"(<shape type="sphere"><ref id="later"/></shape><bsdf type="diffuse" id="later"/>
        <alias id="later" as="other"/><shape type="cube"><ref id="other"/><ref id="lamp"/></shape>
        <emitter type="area" id="lamp"><rgb name="radiance" value="2"/></emitter>)");
    CHECK(sc->shapes().size() == 2);
    CHECK(sc->emitters().size() == 1);
    // pre-2.0 scenes: camelCase names upgraded in memory (Mitsuba's upgrade_tree)
    ParsedScene old = parse_scene_string(R"(<scene version="0.6.0"><shape type="sphere"><bsdf type="diffuse">
        <rgb name="diffuseReflectance" value="0.3"/></bsdf><transform name="toWorld"><lookAt origin="0,0,1" target="0,0,0" up="0,1,0"/>
        </transform></shape></scene>)", "old.xml", {});
    CHECK(old.upgraded);
    CHECK(prop(*old.root->children[0].obj, "to_world") != nullptr);
    CHECK(prop(*old.root->children[0].obj->children[0].obj, "diffuse_reflectance") != nullptr);
    // focal_length: 50mm on 35 mm film = 46.79 degrees diagonal (Mitsuba's default)
    ParsedScene cam = parse_scene_string(R"(<scene version="3.0.0"><sensor type="perspective"><float name="focus_distance" value="3"/>
        <film type="hdrfilm"><integer name="width" value="200"/><integer name="height" value="100"/></film></sensor></scene>)", "c.xml", {});
    auto cs = build_scene(cam, BuildOptions(), nullptr);
    CHECK_NEAR(std::atan(cs->camera.tan_half_x) * 2 * 180 / kPi, 42.3117, 1e-3);  // Mitsuba 3.9.1: x_fov 42.31171
    // rgb outside [0, 1] is refused outside emitters (Mitsuba's RGB variants), allowed for eta
    CHECK_THROWS_WITH(parse("<medium type=\"homogeneous\"><rgb name=\"sigma_t\" value=\"2, 1, 1\"/></medium>"), "outside [0, 1]");
    parse("<bsdf type=\"conductor\"><rgb name=\"eta\" value=\"2, 1, 1\"/></bsdf><emitter type=\"constant\"><rgb name=\"radiance\" value=\"5\"/></emitter>");
}

TEST_CASE(spectra_as_mitsuba_rgb_variants) {
    // Reference values: Mitsuba 3.9.1 scalar_rgb (diffuse reflectance and constant-emitter
    // radiance of the same <spectrum>, evaluated through its Python API); the conversion is a
    // deterministic sum, so 1e-5 covers float rounding only.
    auto value = [](const std::string& xml) {
        ParsedScene s = parse(xml);
        const SceneObject& o = *s.root->children[0].obj;
        return o.props[0].rgb;
    };
    Rgb refl = value(R"(<bsdf type="diffuse"><spectrum name="reflectance" value="400:0.1, 500:0.5, 600:0.8, 700:0.3"/></bsdf>)");
    CHECK_NEAR(refl.r, 0.752187, 1e-5);
    CHECK_NEAR(refl.g, 0.645269, 1e-5);
    CHECK_NEAR(refl.b, 0.271706, 1e-5);
    Rgb white = value(R"(<bsdf type="diffuse"><spectrum name="reflectance" value="360:1, 830:1"/></bsdf>)");
    CHECK_NEAR(white.r, 0.998985, 1e-5);
    CHECK_NEAR(white.b, 0.998802, 1e-5);
    Rgb emit = value(R"(<emitter type="constant"><spectrum name="radiance" value="400:0.1, 500:0.5, 600:0.8, 700:0.3"/></emitter>)");
    CHECK_NEAR(emit.r, 0.883847, 1e-5);
    CHECK_NEAR(emit.g, 0.618319, 1e-5);
    CHECK_NEAR(emit.b, 0.236324, 1e-5);
    // a constant spectrum: grey in a BSDF, the sRGB colour of equal energy in an emitter
    Rgb grey = value(R"(<bsdf type="diffuse"><spectrum name="reflectance" value="0.5"/></bsdf>)");
    CHECK(grey.r == 0.5f && grey.g == 0.5f && grey.b == 0.5f);
    Rgb equal = value(R"(<emitter type="constant"><spectrum name="radiance" value="2"/></emitter>)");
    CHECK_NEAR(equal.r, 2 * 1.20479, 1e-5);
    CHECK_NEAR(equal.g, 2 * 0.948291, 1e-5);
    CHECK_NEAR(equal.b, 2 * 0.908916, 1e-5);
    // above 1: clamped for a reflectance (with a warning), kept for an IOR (Mitsuba: 2.79483, ...)
    ParsedScene clamped = parse(R"(<bsdf type="diffuse"><spectrum name="reflectance" value="400:2, 700:2"/></bsdf>)");
    CHECK(clamped.root->children[0].obj->props[0].rgb.max() == 1.0f);
    CHECK(clamped.warnings.size() == 1);
    Rgb eta = value(R"(<bsdf type="conductor"><spectrum name="eta" value="400:2, 700:3"/><rgb name="k" value="1"/></bsdf>)");
    CHECK_NEAR(eta.r, 2.79483, 1e-4);
    CHECK_NEAR(eta.b, 2.12586, 1e-4);
    // malformed lists are refused with the element's line
    CHECK_THROWS_WITH(parse(R"(<bsdf type="diffuse"><spectrum name="reflectance" value="400:0.1, 500"/></bsdf>)"), "expected wavelength:value");
    CHECK_THROWS_WITH(parse(R"(<bsdf type="diffuse"><spectrum name="reflectance" value="400:0.1"/></bsdf>)"), "at least two");
    CHECK_THROWS_WITH(parse(R"(<bsdf type="diffuse"><spectrum name="reflectance" filename="none.spd"/></bsdf>)"), "not found");
    // a spectrum file (.spd): "wavelength value" lines and comments
    {
        std::string path = std::string(MFHOST_TEST_WORK) + "/test.spd";
        FILE* f = std::fopen(path.c_str(), "w");
        std::fputs("# a test spectrum\n400 0.1\n500 0.5\n\n600 0.8 # peak\n700 0.3\n", f);
        std::fclose(f);
        Rgb file = value("<bsdf type=\"diffuse\"><spectrum name=\"reflectance\" filename=\"" + path + "\"/></bsdf>");
        CHECK_NEAR(file.r, 0.752187, 1e-5);
        CHECK_NEAR(file.b, 0.271706, 1e-5);
    }
}

TEST_CASE(cylinder_instance_and_srgb_spectrum) {
    // Reference hits: Mitsuba 3.9.1 scalar_rgb, cylinder with to_world = scale(1.5, 1.5, 2),
    // ray_intersect from the listed origins. Tolerances: the tessellation (1024 facets) moves the
    // surface by < 5e-6 radii; uv and dp/du come from the analytic parameterization (float).
    auto sc = build(R"(<shape type="cylinder"><transform name="to_world"><scale x="1.5" y="1.5" z="2"/></transform></shape>)");
    struct Ref { Vec3 o, d, p, n; Vec2 uv; Vec3 dpdu; };
    const Ref refs[3] = {
        {Vec3(5, 0.5f, 1), Vec3(-1, 0, 0), Vec3(1.41421f, 0.5f, 1), Vec3(0.942809f, 0.333333f, 0), Vec2(0.0540867f, 0.5f), Vec3(-3.14159f, 8.88577f, 0)},
        {Vec3(0, -5, 0.3f), Vec3(0, 1, 0), Vec3(0, -1.5f, 0.3f), Vec3(0, -1, 0), Vec2(0.75f, 0.15f), Vec3(9.42478f, 0, 0)},
        // from inside: Mitsuba's normal still points outwards
        {Vec3(0, 0, 0.5f), normalize(Vec3(1, 1, 0)), Vec3(1.06066f, 1.06066f, 0.5f), Vec3(0.707107f, 0.707107f, 0), Vec2(0.125f, 0.25f), Vec3(-6.66432f, 6.66432f, 0)}};
    for (const Ref& r : refs) {
        SurfaceHit h;
        CHECK(sc->intersect(Ray(r.o, r.d), &h));
        for (int k = 0; k < 3; ++k) {
            CHECK_NEAR(h.p[k], r.p[k], 2e-5);
            CHECK_NEAR(h.ns[k], r.n[k], 1e-5);
            CHECK_NEAR(h.ng[k], r.n[k], 5e-3);  // a facet's normal: within pi / 1024 of the true one
            CHECK_NEAR(h.dpdu[k], r.dpdu[k], 1e-4);
        }
        CHECK_NEAR(h.uv.x, r.uv.x, 1e-5);
        CHECK_NEAR(h.uv.y, r.uv.y, 1e-5);
    }
    // open ends: a ray along the axis misses
    SurfaceHit miss;
    CHECK(!sc->intersect(Ray(Vec3(0, 0, -5), Vec3(0, 0, 1)), &miss));
    // p0, p1, radius: the axis from p0 to p1
    auto axis = build(R"(<shape type="cylinder"><point name="p0" x="1" y="0" z="0"/><point name="p1" x="3" y="0" z="0"/>
        <float name="radius" value="0.5"/></shape>)");
    SurfaceHit ha;
    CHECK(axis->intersect(Ray(Vec3(2.5f, 0, 5), Vec3(0, 0, -1)), &ha));
    CHECK_NEAR(ha.p.z, 0.5, 1e-5);
    CHECK_NEAR(ha.uv.y, 0.75, 1e-5);  // v = distance along the axis / |p1 - p0|
    CHECK(!axis->intersect(Ray(Vec3(3.5f, 0, 5), Vec3(0, 0, -1)), &miss));
    CHECK_THROWS_WITH(build(R"(<shape type="cylinder"><point name="p1" x="0" y="0" z="0"/></shape>)"), "distinct");

    // instances: every member of the group per instance, placed by instance * member to_world
    auto inst = build(R"(<shape type="shapegroup" id="g">
          <shape type="sphere"><float name="radius" value="0.5"/><transform name="to_world"><translate x="1"/></transform></shape>
          <shape type="rectangle"/></shape>
        <shape type="instance"><ref id="g"/></shape>
        <shape type="instance"><ref id="g"/><transform name="to_world"><scale value="2"/><translate z="10"/></transform></shape>)");
    CHECK(inst->shapes().size() == 4);
    SurfaceHit hi;
    CHECK(inst->intersect(Ray(Vec3(2, 0, 20), Vec3(0, 0, -1)), &hi));  // sphere at (2, 0, 10), radius 1
    CHECK_NEAR(hi.p.z, 11, 1e-5);
    CHECK(inst->intersect(Ray(Vec3(-1.9f, 0, 20), Vec3(0, 0, -1)), &hi));  // rectangle scaled to [-2, 2]^2 at z = 10
    CHECK_NEAR(hi.p.z, 10, 1e-5);
    CHECK(inst->intersect(Ray(Vec3(-0.9f, 0, 5), Vec3(0, 0, -1)), &hi));  // the untransformed instance
    CHECK_NEAR(hi.p.z, 0, 1e-6);
    auto only_group = build(R"(<shape type="shapegroup" id="g"><shape type="sphere"/></shape>)");
    CHECK(only_group->shapes().empty());  // a shapegroup alone renders nothing (as in Mitsuba)
    CHECK_THROWS_WITH(build(R"(<shape type="shapegroup" id="g"><shape type="sphere"><emitter type="area"/></shape></shape>
        <shape type="instance"><ref id="g"/></shape>)"), "cannot be instanced");
    CHECK_THROWS_WITH(build(R"(<shape type="shapegroup" id="g"><shape type="sphere"/></shape>
        <shape type="shapegroup" id="h"><shape type="instance"><ref id="g"/></shape></shape><shape type="instance"><ref id="h"/></shape>)"),
                      "nested instancing");
    CHECK_THROWS_WITH(build(R"(<bsdf type="diffuse" id="b"/><shape type="instance"><ref id="b"/></shape>)"), "shapegroup");

    // <spectrum type="srgb">: the colour itself, bounded like an <rgb> (Mitsuba 3.9.1 refuses
    // color 1.5 in a reflectance: "Invalid RGB reflectance value")
    ParsedScene srgb = parse(R"(<bsdf type="diffuse"><spectrum name="reflectance" type="srgb"><rgb name="color" value="0.5, 0.25, 1"/></spectrum></bsdf>)");
    Rgb c = srgb.root->children[0].obj->props[0].rgb;
    CHECK(c.r == 0.5f && c.g == 0.25f && c.b == 1.0f);
    CHECK_THROWS_WITH(parse(R"(<bsdf type="diffuse"><spectrum name="reflectance" type="srgb"><rgb name="color" value="1.5, 0.2, 0.2"/></spectrum></bsdf>)"),
                      "outside [0, 1]");
    parse(R"(<emitter type="constant"><spectrum name="radiance" type="srgb"><rgb name="color" value="3, 2, 1"/></spectrum></emitter>)");
    CHECK_THROWS_WITH(parse(R"(<bsdf type="diffuse"><spectrum name="reflectance" type="blackbody"/></bsdf>)"), "unsupported spectrum plugin");
    CHECK_THROWS_WITH(parse(R"(<bsdf type="diffuse"><spectrum name="reflectance" type="srgb"/></bsdf>)"), "needs <rgb name=\"color\"");
}

TEST_CASE(mesh_attribute_textures) {
    // Reference values: Mitsuba 3.9.1 scalar_rgb, mesh_attribute eval at ray_intersect of the same
    // PLY (vertex colours interpolated with Embree's barycentrics, uchar values as stored, face
    // colours per face). Tolerance 1e-4 relative: float arithmetic.
    const std::string path = std::string(MFHOST_TEST_WORK) + "/attr.ply";
    {
        FILE* f = std::fopen(path.c_str(), "w");
        std::fputs("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                   "property uchar r\nproperty uchar g\nproperty uchar b\nelement face 2\n"
                   "property list uchar int vertex_indices\nproperty float r\nproperty float g\nproperty float b\nend_header\n"
                   "-1 -1 0 255 0 0\n1 -1 0 0 128 0\n1 1 0 0 0 64\n-1 1 0 10 20 30\n"
                   "3 0 1 2 0.9 0.5 0.1\n3 0 2 3 0.2 0.3 0.4\n", f);
        std::fclose(f);
    }
    auto reflectance = [&](const std::string& name, const Vec3& o) {
        auto sc = build("<shape type=\"ply\"><string name=\"filename\" value=\"" + path +
                        "\"/><bsdf type=\"diffuse\"><texture name=\"reflectance\" type=\"mesh_attribute\"><string name=\"name\" value=\"" +
                        name + "\"/></texture></bsdf></shape>");
        SurfaceHit h;
        CHECK(sc->intersect(Ray(o, Vec3(0, 0, -1)), &h));
        return h.shape->bsdf->eval(h.texture_point(), Vec3(0, 0, 1), Vec3(0, 0, 1)) * kPi;
    };
    Rgb v = reflectance("vertex_color", Vec3(0.9f, -0.9f, 1));
    CHECK_NEAR(v.r, 12.75, 2e-3);
    CHECK_NEAR(v.g, 115.2, 2e-2);
    CHECK_NEAR(v.b, 3.2, 1e-3);
    Rgb fc = reflectance("face_color", Vec3(0.9f, -0.9f, 1));
    CHECK_NEAR(fc.r, 0.9, 1e-5);
    CHECK_NEAR(fc.b, 0.1, 1e-5);
    Rgb fc2 = reflectance("face_color", Vec3(-0.5f, 0.5f, 1));
    CHECK_NEAR(fc2.g, 0.3, 1e-5);
    // a shape without the attribute, or another attribute name, is refused with the element
    CHECK_THROWS_WITH(build(R"(<shape type="sphere"><bsdf type="diffuse"><texture name="reflectance" type="mesh_attribute">
        <string name="name" value="vertex_color"/></texture></bsdf></shape>)"), "has no mesh attribute");
    CHECK_THROWS_WITH(build(R"(<texture type="mesh_attribute" id="t"><string name="name" value="vertex_weight"/></texture>)"),
                      "vertex_color or face_color");
}

TEST_MAIN()
