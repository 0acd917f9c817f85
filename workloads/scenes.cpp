#include "scenes.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <sstream>

#include <array>
#include <functional>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/trigonometric.hpp>

#include "input_error.h"
#include "file_io.h"
#include "mesh_io.h"

namespace fs = std::filesystem;

namespace rtu {
namespace {

// LumiBench's placement of a model (RayTracingInVulkan src/SceneList.cpp, e.g. l.325-330):
// rotate(scale(translate(I, t), s), radians(deg), +Y) in GLM's float arithmetic, baked into the
// vertices (Model::Transform): a vertex is rotated about +Y, then scaled, then translated.
glm::mat4 lumibench_placement(glm::vec3 t, float s, float deg) {
    return glm::rotate(glm::scale(glm::translate(glm::mat4(1.0f), t), glm::vec3(s)), glm::radians(deg), glm::vec3(0, 1, 0));
}

void bake(Mesh& m, const glm::mat4& M) { bake_transform(m, glm::value_ptr(M)); }

// Moves the mesh's bounding-box bottom centre to the origin and scales its height to 1 (the
// shared stand-ins are in their scanners' units; the scenes README).
void normalise_height(Mesh& m) {
    const Aabb b = m.bounds();
    const float h = b.hi.y - b.lo.y;
    const float s = h > 0.0f ? 1.0f / h : 1.0f;
    const glm::vec3 c(0.5f * (b.lo.x + b.hi.x), b.lo.y, 0.5f * (b.lo.z + b.hi.z));
    bake(m, glm::translate(glm::scale(glm::mat4(1.0f), glm::vec3(s)), -c));
}

Material lambertian(glm::vec3 albedo) {
    Material m;
    m.albedo = albedo;
    return m;
}
Material metallic(glm::vec3 albedo, float fuzz) {
    Material m;
    m.kind = Material::Kind::Metal;
    m.albedo = albedo;
    m.fuzz = fuzz;
    return m;
}
Material dielectric(float ior) {
    Material m;
    m.kind = Material::Kind::Glass;
    m.ior = ior;
    return m;
}
Material diffuse_light(float e) {
    Material m;
    m.kind = Material::Kind::Emitter;
    m.emission = glm::vec3(e);
    m.albedo = glm::vec3(e);  // LumiBench's DiffuseLight keeps the emission as its colour
    return m;
}

// Model::SetMaterial(m, i) and SetAllMaterial(m) (Model.cpp l.764-784): the model's material i of
// its file's library, or every one of them.
void set_material(Scene& s, const Mesh& mesh, size_t i, const Material& m) {
    if (i < mesh.file_materials.size()) s.materials[mesh.file_materials[i]] = m;
}
void set_all_materials(Scene& s, const Mesh& mesh, const Material& m) {
    for (size_t i = 0; i < mesh.file_materials.size(); ++i) set_material(s, mesh, i, m);
}

// Model::CreateSphere(center, r, material, procedural) as one model of its own.
void add_sphere_model(Scene& s, const std::string& name, glm::vec3 c, float r, const Material& mat) {
    Mesh m;
    m.name = name;
    m.spheres.push_back({c, r});
    m.material.push_back(add_material(s, mat));
    m.file_materials = m.material;
    s.meshes.push_back(std::move(m));
}

// LumiBench's CornellBox::Create (src/Assets/CornellBox.cpp): one model of 12 triangles, each
// panel with its inward normal at every vertex; materials red, green, white, light (15).
// `mirror_sides` (REF, SceneList.cpp l.1281-1282): the red and green walls become perfect mirrors.
void add_cornell_box(Scene& s, bool mirror_sides) {
    const glm::vec3 red(0.65f, 0.05f, 0.05f), green(0.12f, 0.45f, 0.15f);
    const uint32_t mr = add_material(s, mirror_sides ? metallic(red, 0.0f) : lambertian(red));
    const uint32_t mg = add_material(s, mirror_sides ? metallic(green, 0.0f) : lambertian(green));
    const uint32_t mw = add_material(s, lambertian(glm::vec3(0.73f))), ml = add_material(s, diffuse_light(15.0f));
    Mesh m;
    m.name = "cornell-box";
    m.file_materials = {mr, mg, mw, ml};
    const float L = 555.0f;
    const glm::vec3 l0(0, 0, 0), l1(0, 0, -L), l2(0, L, -L), l3(0, L, 0), r0(L, 0, 0), r1(L, 0, -L), r2(L, L, -L), r3(L, L, 0);
    // A panel: four vertices with one normal, two triangles as CornellBox.cpp orders them.
    auto panel = [&](std::array<glm::vec3, 4> v, glm::vec3 n, std::array<glm::uvec3, 2> tris, uint32_t mat) {
        const uint32_t base = uint32_t(m.vertices.size());
        for (const glm::vec3& p : v) {
            m.vertices.push_back(p);
            m.normals.push_back(n);
        }
        for (const glm::uvec3& t : tris) {
            m.triangles.push_back(t + glm::uvec3(base));
            m.material.push_back(mat);
        }
    };
    const std::array<glm::uvec3, 2> ccw{glm::uvec3(0, 1, 2), glm::uvec3(0, 2, 3)};
    panel({l0, l1, l2, l3}, {1, 0, 0}, ccw, mg);                                       // left, green
    panel({r0, r1, r2, r3}, {-1, 0, 0}, {glm::uvec3(2, 1, 0), glm::uvec3(3, 2, 0)}, mr);  // right, red
    panel({l1, r1, r2, l2}, {0, 0, 1}, ccw, mw);                                       // back
    panel({l0, r0, r1, l1}, {0, 1, 0}, ccw, mw);                                       // floor
    panel({l2, r2, r3, l3}, {0, -1, 0}, ccw, mw);                                      // ceiling
    const float x0 = L * (213.0f / 555.0f), x1 = L * (343.0f / 555.0f);
    const float z0 = L * (-555.0f + 332.0f) / 555.0f, z1 = L * (-555.0f + 227.0f) / 555.0f, y1 = L * 0.998f;
    panel({glm::vec3(x0, y1, z1), glm::vec3(x1, y1, z1), glm::vec3(x1, y1, z0), glm::vec3(x0, y1, z0)}, {0, -1, 0}, ccw, ml);  // light
    s.meshes.push_back(std::move(m));
}

// LumiBench's cameras: lookAt(eye, look-at, +Y) and a vertical field of view.
Camera lumibench_camera(glm::vec3 eye, glm::vec3 lookat, float vfov, float aperture = 0.0f, float focus = 10.0f) {
    Camera c;
    c.eye = eye;
    c.lookat = lookat;
    c.vfov = vfov;
    c.aperture = aperture;
    c.focus_dist = focus;
    return c;
}

std::vector<std::string> mesh_files_in(const std::string& dir) {
    std::vector<std::string> names;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
        const std::string n = e.path().filename().string();
        const bool mesh = e.path().extension() == ".obj" || e.path().extension() == ".ply" ||
                          (n.size() > 7 && n.compare(n.size() - 7, 7, ".ply.gz") == 0);
        // Without throwing: a link that loops or leads nowhere must not end the run as an
        // internal error. Anything but a mesh file is passed over; a mesh's name that is not a
        // readable file is refused, since leaving it out would renumber the scene's geometry.
        std::error_code link;
        const bool file = e.is_regular_file(link);
        if (!mesh) continue;
        if (!file) {
            std::error_code l2;
            throw input_error(e.path().string(), 0,
                              e.is_symlink(l2) ? "a symbolic link that loops or leads nowhere; fix or remove it (the scene's files are numbered in name order)"
                                               : "not a regular file; rename or remove it (the scene's files are numbered in name order)");
        }
        names.push_back(n);
    }
    if (ec) throw input_error(dir, 0, "cannot list folder: " + ec.message());
    std::sort(names.begin(), names.end());  // byte-wise (LumiBench takes the file system's order, which it does not fix)
    return names;
}

std::string find_camera_file(const std::string& dir) {
    std::vector<std::string> cams;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec))
        if (e.path().extension() == ".camera") cams.push_back(e.path().string());
    std::sort(cams.begin(), cams.end());
    return cams.empty() ? std::string() : cams.front();
}

// A folder of mesh files, one model each; `keep(file, mesh)` decides whether a loaded file is
// kept (LumiBench's SPRNG drops empty files and Dirt_grass*).
Scene load_folder(const std::string& dir, float vfov, bool tinyobj,
                  const std::function<bool(const std::string&, const Mesh&)>& keep = nullptr) {
    Scene s;
    s.name = dir;
    const auto files = mesh_files_in(dir);
    if (files.empty()) throw input_error(dir, 0, "folder holds no mesh files (.obj, .ply, .ply.gz)");
    for (const auto& f : files) {
        load_mesh_file(s, (fs::path(dir) / f).string(), {}, tinyobj);
        if (keep && !keep(f, s.meshes.back())) s.meshes.pop_back();
    }
    add_identity_instances(s);
    const std::string cam = find_camera_file(dir);
    s.camera = cam.empty() ? default_camera(s.world_bounds()) : read_camera_file(cam, vfov);
    if (!cam.empty()) s.camera.focus_dist = 7.0f;  // LumiBench's folder scenes; no lens (aperture 0)
    return s;
}

bool contains(const std::string& s, const char* part) { return s.find(part) != std::string::npos; }

// LumiBench's BATH materials (SceneList.cpp l.1313-1359), by file name.
void bath_materials(Scene& s) {
    const auto c = [](int r, int g, int b) { return glm::vec3(float(r / 256.0), float(g / 256.0), float(b / 256.0)); };
    const Material chrome = metallic(glm::vec3(0.73f), 0.0f);
    for (const Mesh& m : s.meshes) {
        const std::string f = fs::path(m.name).filename().string();
        if (f == "sol.obj") {
            set_material(s, m, 0, diffuse_light(15.0f));
            set_material(s, m, 1, lambertian(c(44, 26, 12)));
            set_material(s, m, 2, chrome);
            set_material(s, m, 4, lambertian(c(226, 243, 227)));
            set_material(s, m, 5, lambertian(c(196, 137, 88)));
        } else if (contains(m.name, "Meuble") || contains(m.name, "meuble") || contains(m.name, "baignoire")) {
            set_all_materials(s, m, lambertian(c(196, 137, 88)));
        } else if (contains(m.name, "statu")) {
            set_all_materials(s, m, lambertian(c(14, 6, 3)));
        } else if (contains(m.name, "robinet") || contains(m.name, "etend_serviette")) {
            set_all_materials(s, m, chrome);
        } else if (f == "prise.obj") {
            set_material(s, m, 0, lambertian(c(164, 150, 134)));
            set_material(s, m, 1, lambertian(c(34, 22, 13)));
        } else if (contains(m.name, "poubelle")) {
            set_material(s, m, 0, chrome);
            set_material(s, m, 1, lambertian(c(14, 5, 4)));
        } else if (contains(m.name, "pese_personne")) {
            set_material(s, m, 1, lambertian(c(14, 5, 4)));
        } else if (contains(m.name, "bouteille")) {
            set_material(s, m, 2, lambertian(c(93, 77, 62)));
        } else if (contains(m.name, "emit_haut")) {
            set_all_materials(s, m, diffuse_light(15.0f));
        }
    }
}

// LumiBench's SPRNG materials (SceneList.cpp l.768-799), by file name, first match.
void sprng_materials(Scene& s) {
    const auto c = [](int r, int g, int b) { return glm::vec3(float(r / 256.0), float(g / 256.0), float(b / 256.0)); };
    const std::pair<std::vector<const char*>, glm::vec3> rules[] = {
        {{"spring_body"}, c(223, 175, 171)},   {{"stitches"}, c(92, 64, 51)},        {{"spring_jacket"}, c(163, 67, 42)},
        {{"spring_pants"}, c(92, 74, 101)},    {{"spring_boots"}, c(150, 106, 86)},  {{"spring_hairband"}, c(69, 23, 8)},
        {{"spring_hair"}, c(108, 86, 99)},     {{"spring_scarf", "spring_pullover"}, c(114, 76, 64)},
    };
    for (const Mesh& m : s.meshes)
        for (const auto& [parts, colour] : rules)
            if (std::any_of(parts.begin(), parts.end(), [&](const char* p) { return contains(m.name, p); })) {
                set_all_materials(s, m, lambertian(colour));
                break;
            }
}

std::string require_assets(const std::string& name, const std::string& assets) {
    if (assets.empty())
        throw InputError("scene '" + name + "' needs its asset folder: --assets DIR (e.g. ../shared/scenes/" +
                         (name.rfind("ref", 0) == 0 ? std::string("dragon") : name) + ")");
    std::error_code ec;
    if (!fs::is_directory(assets, ec)) throw input_error(assets, 0, "asset folder not found");
    return assets;
}

std::string require_file(const std::string& dir, const std::vector<std::string>& candidates) {
    for (const auto& c : candidates) {
        const std::string p = (fs::path(dir) / c).string();
        std::error_code ec;
        if (fs::is_regular_file(p, ec)) return p;
    }
    std::string list;
    for (const auto& c : candidates) list += (list.empty() ? "" : ", ") + c;
    throw input_error(dir, 0, "expected one of: " + list);
}

}  // namespace

Scene make_wknd() {
    // SceneList.cpp l.21-64 and l.131-158: every sphere a model of its own, in this order.
    Scene s;
    s.name = "wknd";
    std::mt19937 gen(42);
    std::uniform_real_distribution<float> dist;  // [0, 1), one 32-bit draw a call with libstdc++
    auto rnd = [&] { return dist(gen); };
    add_sphere_model(s, "ground", {0, -1000, 0}, 1000, lambertian(glm::vec3(0.5f)));
    for (int i = -11; i < 11; ++i) {
        for (int j = -11; j < 11; ++j) {
            const float choose = rnd();
            const float z = float(j) + 0.9f * rnd();  // LumiBench's `center_y`, drawn before x
            const float x = float(i) + 0.9f * rnd();
            const glm::vec3 c(x, 0.2f, z);
            if (!(glm::length(c - glm::vec3(4, 0.2f, 0)) > 0.9f)) continue;
            const std::string name = "sphere-" + std::to_string(s.meshes.size());
            if (choose < 0.8f) {
                const float b = rnd() * rnd(), g = rnd() * rnd(), r = rnd() * rnd();  // each product's draws in turn
                add_sphere_model(s, name, c, 0.2f, lambertian({r, g, b}));
            } else if (choose < 0.95f) {
                const float fuzz = 0.5f * rnd();
                const float b = 0.5f * (1 + rnd()), g = 0.5f * (1 + rnd()), r = 0.5f * (1 + rnd());
                add_sphere_model(s, name, c, 0.2f, metallic({r, g, b}, fuzz));
            } else {
                add_sphere_model(s, name, c, 0.2f, dielectric(1.5f));
            }
        }
    }
    add_sphere_model(s, "glass", {0, 1, 0}, 1.0f, dielectric(1.5f));
    add_sphere_model(s, "diffuse", {-4, 1, 0}, 1.0f, lambertian({0.4f, 0.2f, 0.1f}));
    add_sphere_model(s, "metal", {4, 1, 0}, 1.0f, metallic({0.7f, 0.6f, 0.5f}, 0.0f));
    add_identity_instances(s);
    s.camera = lumibench_camera({13, 2, 3}, {0, 0, 0}, 20, 0.1f, 10.0f);
    s.sky = true;
    return s;
}

Scene make_cornell() {
    // LumiBench's CornellBox scene (SceneList.cpp): the box alone, no sky.
    Scene s;
    s.name = "cornell";
    add_cornell_box(s, false);
    add_identity_instances(s);
    s.camera = lumibench_camera({278, 278, 800}, {278, 278, 0}, 40);
    s.sky = false;
    s.light = glm::vec3(278, 553, -275.5f);
    s.light_radius = 50;
    return s;
}

Camera read_camera_file(const std::string& path, float vfov) {
    std::istringstream in(read_file_maybe_gz(path));
    Camera c;
    c.vfov = vfov;
    std::string line;
    glm::vec3* targets[2] = {&c.eye, &c.lookat};
    size_t lineno = 0;
    for (int k = 0; k < 2; ++k) {
        do {
            if (!std::getline(in, line)) throw input_error(path, lineno, "camera file needs two lines: eye xyz, look-at xyz");
            ++lineno;
        } while (line.find_first_not_of(" \t\r") == std::string::npos);
        std::istringstream ls(line);
        glm::vec3& v = *targets[k];
        if (!(ls >> v.x >> v.y >> v.z) || !std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
            throw input_error(path, lineno, "expected three finite numbers, got '" + line + "'");
    }
    c.focus_dist = glm::length(c.lookat - c.eye);
    if (!(c.focus_dist > 0.0f)) throw input_error(path, 0, "eye and look-at coincide");
    return c;
}

std::vector<std::string> scene_names() { return {"wknd", "cornell", "ship", "bunny", "ref", "ref-full", "bath", "sprng", "party"}; }

Scene load_scene(const std::string& name, const std::string& assets) {
    // LumiBench's scenes as its SceneList.cpp builds them: every model (an OBJ file, the Cornell
    // box, a procedural sphere) its own BLAS under one TLAS, placed by transforms baked into its
    // vertices; docs/lumibench.md gives each choice's source.
    Scene s;
    if (name == "wknd") {
        s = make_wknd();
    } else if (name == "cornell") {
        s = make_cornell();
    } else if (name == "ship") {  // SceneList.cpp l.310-335
        const std::string dir = require_assets(name, assets);
        load_mesh_file(s, require_file(dir, {"karimSchooner.obj"}), {}, true);
        bake(s.meshes[0], lumibench_placement({173, -9, -377}, 100, 75));
        s.camera = lumibench_camera({378, 278, 500}, {178, 278, 0}, 50);
        s.sky = true;
    } else if (name == "bunny") {  // l.337-363: the box first, then the bunny
        const std::string dir = require_assets(name, assets);
        add_cornell_box(s, false);
        load_mesh_file(s, require_file(dir, {"stanford-bunny.obj", "bunny.obj", "bun_zipper.ply"}), {}, true);
        normalise_height(s.meshes[1]);
        bake(s.meshes[1], lumibench_placement({173, 5, -307}, 200, 75));
        s.camera = lumibench_camera({278, 278, 800}, {278, 278, 0}, 40);
        s.sky = false;
        s.light = glm::vec3(280, 500, 400);
        s.light_radius = 10;
    } else if (name == "ref" || name == "ref-full") {  // l.1251-1291: box (mirrors), glass sphere, statue
        // ref: the 202 k-triangle dragon in place of LumiBench's Lucy; ref-full: the 871 k-triangle one.
        const std::string dir = require_assets(name, assets);
        add_cornell_box(s, true);
        add_sphere_model(s, "glass-sphere", {425, 165, -147.5f}, 80, dielectric(1.5f));
        if (name == "ref")
            load_mesh_file(s, require_file(dir, {"dragon_vrip_res2.ply.gz", "dragon_vrip.ply.gz", "dragon_vrip_res2.ply", "dragon_vrip.ply"}));
        else
            load_mesh_file(s, require_file(dir, {"dragon_vrip.ply.gz", "dragon_vrip.ply"}));
        // Our placement of the stand-in (Lucy's own differs): height 200, on the floor left of
        // the glass sphere.
        normalise_height(s.meshes[2]);
        bake(s.meshes[2], lumibench_placement({230, 0, -330}, 200, 75));
        s.camera = lumibench_camera({278, 278, 350}, {278, 278, 0}, 78);
        s.sky = false;
        s.light = glm::vec3(280, 500, 280);
        s.light_radius = 10;
    } else if (name == "bath") {  // l.1293-1378
        s = load_folder(require_assets(name, assets), 36, true);
        bath_materials(s);
        s.sky = true;
        const Aabb b = s.world_bounds();  // no light position in LumiBench's BATH: the shadow workload's is ours
        s.light = glm::vec3(0.5f * (b.lo.x + b.hi.x), b.hi.y - 0.05f * (b.hi.y - b.lo.y), 0.5f * (b.lo.z + b.hi.z));
    } else if (name == "sprng") {  // l.738-820: files without vertices and Dirt_grass* are left out
        s = load_folder(require_assets(name, assets), 20, true,
                        [](const std::string& f, const Mesh& m) { return !m.vertices.empty() && f.find("Dirt_grass") == std::string::npos; });
        sprng_materials(s);
        s.sky = true;
    } else if (name == "party") {  // l.822-863, without its characters (shared/scenes/README.md)
        s = load_folder(require_assets(name, assets), 20, true);
        s.sky = true;
    } else {
        std::error_code ec;
        if (fs::is_directory(name, ec)) {
            s = load_folder(name, 45, false);
        } else if (fs::exists(name, ec)) {
            load_mesh_file(s, name);
            add_identity_instances(s);
            s.camera = default_camera(s.world_bounds());
        } else if (fs::is_symlink(name, ec)) {
            throw InputError("--scene '" + name + "': a symbolic link that loops or leads nowhere");
        } else {
            std::string names;
            for (const auto& n : scene_names()) names += (names.empty() ? "" : ", ") + n;
            throw InputError("--scene '" + name + "': no such file or folder, and not a scene name (" + names + ")");
        }
        s.sky = true;
    }
    if (s.instances.empty()) add_identity_instances(s);
    if (s.name.empty() || name == "bath" || name == "sprng" || name == "party") s.name = name;
    s.validate();
    return s;
}

}  // namespace rtu
