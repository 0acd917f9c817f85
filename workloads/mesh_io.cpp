#include "mesh_io.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <limits>
#include <array>
#include <map>
#include <set>
#include <string_view>
#include <type_traits>

#include <absl/container/flat_hash_map.h>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include "file_io.h"
#include "input_error.h"

namespace fs = std::filesystem;

namespace rtu {
namespace {

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
    return s;
}

// Extension without a trailing ".gz", lower case, e.g. "obj" for "a.OBJ.gz".
std::string mesh_extension(const std::string& path) {
    std::string p = lower(fs::path(path).filename().string());
    if (p.size() > 3 && p.compare(p.size() - 3, 3, ".gz") == 0) p.resize(p.size() - 3);
    const auto dot = p.rfind('.');
    return dot == std::string::npos ? std::string() : p.substr(dot + 1);
}

// Parses a whole token as a number (float, double or long); false if it is not one. From_chars
// first (no allocation, no locale); what it does not take (a leading '+', hexadecimal, out of
// range) goes to strtof / strtod / strtol as it always did, so every token reads as before.
template <class T>
bool parse_number(std::string_view tok, T* out) {
    if (tok.empty()) return false;
    T v;
    const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), v);
    if (r.ec == std::errc() && r.ptr == tok.data() + tok.size()) {
        *out = v;
        return true;
    }
    const std::string s(tok);
    char* end = nullptr;
    errno = 0;
    if constexpr (std::is_same_v<T, float>) v = std::strtof(s.c_str(), &end);
    else if constexpr (std::is_same_v<T, double>) v = std::strtod(s.c_str(), &end);
    else v = std::strtol(s.c_str(), &end, 10);
    if (end != s.c_str() + s.size()) return false;
    *out = v;
    return true;
}
bool parse_float(std::string_view tok, float* out) { return parse_number(tok, out); }

void check_finite(const std::string& file, size_t line, std::string_view tok, float v) {
    if (!std::isfinite(v))
        throw input_error(file, line, "vertex coordinate '" + std::string(tok) + "' is not finite (NaN or infinity)");
}

// std::isspace in the "C" locale, which rtsim never leaves: space, \t, \n, \v, \f and \r (9-13).
// Inline: the library call per character took a fifth of the OBJ reader's time (party, 68 MB).
constexpr bool is_space(unsigned char c) { return c == ' ' || (c >= '\t' && c <= '\r'); }

// Whitespace-separated tokens of `s`, as views into it, into `out` (reused: no allocation per
// line once it has grown; string streams, then a vector of strings, dominated load times).
void split(std::string_view s, std::vector<std::string_view>& out) {
    out.clear();
    const size_t n = s.size();
    size_t i = 0;
    while (i < n) {
        while (i < n && is_space(static_cast<unsigned char>(s[i]))) ++i;
        size_t j = i;
        while (j < n && !is_space(static_cast<unsigned char>(s[j]))) ++j;
        if (j > i) out.push_back(s.substr(i, j - i));
        i = j;
    }
}
std::vector<std::string_view> split(std::string_view s) {
    std::vector<std::string_view> out;
    split(s, out);
    return out;
}

// Next line of `data` from `pos` (without its newline), as a view into `data`; false at the end.
bool next_line(const std::string& data, size_t& pos, std::string_view& line) {
    if (pos >= data.size()) return false;
    const size_t nl = data.find('\n', pos);
    const size_t end = nl == std::string::npos ? data.size() : nl;
    line = std::string_view(data).substr(pos, end - pos);
    pos = end + 1;
    return true;
}

void fan(Mesh& m, const std::vector<uint32_t>& poly, uint32_t material) {
    for (size_t k = 1; k + 1 < poly.size(); ++k) {
        m.triangles.push_back({poly[0], poly[k], poly[k + 1]});
        m.material.push_back(material);
    }
}

// --- OBJ -------------------------------------------------------------------------------------

// The statements of the MTL format (Wavefront's, with the common PBR extensions): anything else
// in a material library is not one.
bool is_mtl_statement(std::string_view k) {
    static const std::set<std::string_view> known = {"newmtl", "Ka", "Kd", "Ks", "Ke", "Kt", "Ns", "Ni", "d", "Tr", "Tf", "illum",
                                                     "sharpness", "bump", "disp", "decal", "refl", "norm", "Pr", "Pm", "Ps",
                                                     "Pc", "Pcr", "aniso", "anisor"};
    return known.count(k) || k.substr(0, 4) == "map_";
}

// Materials as LumiBench's model loader reads them (RayTracingInVulkan src/Assets/Model.cpp
// l.68-78): each material of the library becomes a Lambertian of its Kd; every other field (Ks,
// Ke, Ni, illum, d) is ignored. `order` receives the materials' indices in library order.
void load_mtl(Scene& scene, const std::string& path, std::map<std::string, uint32_t>& by_name, std::vector<uint32_t>& order) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
        std::cerr << "warning: " << path << ": material library not found, using default materials\n";
        return;
    }
    const std::string data = read_file_maybe_gz(path);
    size_t pos = 0;
    std::string_view line;
    std::vector<std::string_view> t;
    std::vector<Material> mats;
    size_t lineno = 0, statements = 0, unknown = 0, first_unknown = 0;
    while (next_line(data, pos, line)) {
        ++lineno;
        const auto hash = line.find('#');
        if (hash != std::string::npos) line = line.substr(0, hash);
        split(line, t);
        if (t.empty()) continue;
        ++statements;
        if (!is_mtl_statement(t[0]) && unknown++ == 0) first_unknown = lineno;
        if (t[0] == "newmtl") {
            mats.push_back(Material{});
            mats.back().name = t.size() > 1 ? std::string(t[1]) : "";
        } else if (!mats.empty() && t[0] == "Kd") {
            glm::vec3 v(0.0f);
            for (int i = 0; i < 3 && i + 1 < int(t.size()); ++i)
                if (!parse_float(t[i + 1], &v[i])) throw input_error(path, lineno, "bad number '" + std::string(t[i + 1]) + "'");
            mats.back().albedo = v;
        }
    }
    // A library that is not one (a binary or a text of another kind) is read as no materials or
    // as a few by chance: said, since the scene's colours then are not the file's. An empty one
    // (comments only: Blender writes them for objects without faces) is not worth a word.
    if (data.find('\0') != std::string::npos)
        std::cerr << "warning: " << path << ": binary data, not a material library; its materials are ignored\n";
    else if (unknown)
        std::cerr << "warning: " << path << ": " << unknown << " of " << statements
                  << " statements are not material statements (the first at line " << first_unknown << "); they are ignored\n";
    if (mats.empty() && statements > 0) std::cerr << "warning: " << path << ": no material defined (no newmtl line); the faces take the default material\n";
    for (Material& m : mats) {
        const uint32_t i = add_material(scene, m);
        by_name[m.name] = i;
        order.push_back(i);
    }
}

// A face's corner: its position, texture and normal indices (0-based; -1 when absent).
struct Corner {
    long v, vt, vn;
};

// Reads "v", "v/vt", "v//vn" or "v/vt/vn" with 1-based or negative indices against the counts so
// far. A bad position index is an error; a texture or normal index out of range is taken as
// absent (the corner then gets a smooth normal).
Corner parse_corner(std::string_view tok, long nv, long nvt, long nvn, const std::string& path, size_t lineno) {
    Corner c{-1, -1, -1};
    long* out[3] = {&c.v, &c.vt, &c.vn};
    const long count[3] = {nv, nvt, nvn};
    for (int k = 0; k < 3 && !tok.empty(); ++k) {
        const size_t slash = tok.find('/');
        const std::string_view part = tok.substr(0, slash);
        const std::string_view whole = tok;
        tok = slash == std::string_view::npos ? std::string_view() : tok.substr(slash + 1);
        if (part.empty()) {
            if (k == 0) throw input_error(path, lineno, "bad face index '" + std::string(whole) + "'");
            continue;
        }
        long v = 0;
        if (!parse_number(part, &v)) throw input_error(path, lineno, "bad face index '" + std::string(k == 0 ? whole.substr(0, slash) : part) + "'");
        const long i = v > 0 ? v - 1 : count[k] + v;
        if (v == 0 || i < 0 || i >= count[k]) {
            if (k == 0)
                throw input_error(path, lineno, "face index '" + std::string(part) + "' out of range (1.." + std::to_string(count[k]) + ")");
            continue;
        }
        *out[k] = i;
    }
    return c;
}

// tinyobjloader's point-in-polygon test (W. R. Franklin's crossing test, tiny_obj_loader.h
// l.1388-1398) on a triangle: whether (x, y) lies inside, boundary points by its half-open rule.
bool crossing_inside(const float vx[3], const float vy[3], float x, float y) {
    bool inside = false;
    for (int i = 0, j = 2; i < 3; j = i++)
        if ((vy[i] > y) != (vy[j] > y) && x < (vx[j] - vx[i]) * (y - vy[i]) / (vy[j] - vy[i]) + vx[i]) inside = !inside;
    return inside;
}

// A polygon of five or more corners as LumiBench's loader clips its ears (tinyobjloader
// 2.0.0rc10 built without TINYOBJLOADER_USE_MAPBOX_EARCUT, as Debian's libtinyobjloader is:
// tiny_obj_loader.h l.1689-1910, in float). The polygon is projected on two
// axes chosen from the first corner whose edges are not parallel; then, from corner 0, a corner
// triple (g, g+1, g+2) of what remains is cut off as a triangle unless its turn has the other
// sign than (p_g x p_g+1) -- the loader compares with that product of the two positions, not with
// the polygon's winding -- or another remaining corner lies inside it; otherwise the next triple
// is tried. A polygon that runs out of tries with more than three corners left loses them, as
// there. The signs are of float products taken in the loader's order, so a near-degenerate
// triple goes the same way as there where neither build fuses a multiply and an add (x86-64's
// baseline has no FMA); tests/test_tinyobj.cpp compares with the loader on the machine it runs on.
void clip_ears(const std::vector<Corner>& poly, const std::vector<glm::vec3>& pos, std::vector<std::array<size_t, 3>>& out) {
    const size_t n = poly.size();
    const auto at = [&](size_t k) { return pos[size_t(poly[k].v)]; };
    int ax0 = 1, ax1 = 2;
    for (size_t k = 0; k < n; ++k) {
        // The loader's |e0 x e1| by components: the same products and differences as glm::cross.
        const glm::vec3 c = glm::abs(glm::cross(at((k + 1) % n) - at(k), at((k + 2) % n) - at((k + 1) % n)));
        const float eps = std::numeric_limits<float>::epsilon();
        if (c.x > eps || c.y > eps || c.z > eps) {
            if (!(c.x > c.y && c.x > c.z)) {
                ax0 = 0;
                if (c.z > c.x && c.z > c.y) ax1 = 1;
            }
            break;
        }
    }
    std::vector<size_t> left(n);
    for (size_t k = 0; k < n; ++k) left[k] = k;
    size_t guess = 0, tries = n, before = n;
    while (left.size() > 3 && tries > 0) {
        const size_t m = left.size();
        if (guess >= m) guess -= m;
        if (before != m) before = tries = m;
        else --tries;
        size_t idx[3];
        float vx[3], vy[3];
        for (int k = 0; k < 3; ++k) {
            idx[k] = left[(guess + size_t(k)) % m];
            vx[k] = at(idx[k])[ax0];
            vy[k] = at(idx[k])[ax1];
        }
        const float turn = (vx[1] - vx[0]) * (vy[2] - vy[1]) - (vy[1] - vy[0]) * (vx[2] - vx[1]);
        const float area = (vx[0] * vy[1] - vy[0] * vx[1]) * 0.5f;
        if (turn * area < 0.0f) {
            ++guess;
            continue;
        }
        bool overlap = false;
        for (size_t o = 3; o < m && !overlap; ++o) {
            const glm::vec3 p = at(left[(guess + o) % m]);
            overlap = crossing_inside(vx, vy, p[ax0], p[ax1]);
        }
        if (overlap) {
            ++guess;
            continue;
        }
        out.push_back({idx[0], idx[1], idx[2]});
        left.erase(left.begin() + std::ptrdiff_t((guess + 1) % m));
    }
    if (left.size() == 3) out.push_back({left[0], left[1], left[2]});
}

// The triangles of a polygon, as corner indices into it: a fan (v0,v1,v2), (v0,v2,v3), ...; with
// `tinyobj` as LumiBench's loader (tinyobjloader 2.0.0rc10) makes them: a quad split along its
// shorter diagonal (tiny_obj_loader.h l.1463-1550), (0,1,2), (0,2,3) if |v2 - v0| < |v3 - v1|,
// else (0,1,3), (1,2,3); a larger polygon's ears clipped (clip_ears).
void triangulate(const std::vector<Corner>& poly, const std::vector<glm::vec3>& pos, bool tinyobj, std::vector<std::array<size_t, 3>>& out) {
    out.clear();
    if (tinyobj && poly.size() == 4) {
        const glm::vec3 e02 = pos[size_t(poly[2].v)] - pos[size_t(poly[0].v)], e13 = pos[size_t(poly[3].v)] - pos[size_t(poly[1].v)];
        const float sqr02 = e02.x * e02.x + e02.y * e02.y + e02.z * e02.z, sqr13 = e13.x * e13.x + e13.y * e13.y + e13.z * e13.z;
        if (sqr02 < sqr13) out = {{0, 1, 2}, {0, 2, 3}};
        else out = {{0, 1, 3}, {1, 2, 3}};
        return;
    }
    if (tinyobj && poly.size() > 4) {
        clip_ears(poly, pos, out);
        return;
    }
    for (size_t k = 1; k + 1 < poly.size(); ++k) out.push_back({0, k, k + 1});
}

void load_obj(Scene& scene, Mesh& mesh, const std::string& path, bool tinyobj) {
    const std::string data = read_file_maybe_gz(path);
    size_t pos = 0;
    std::map<std::string, uint32_t> materials;
    std::vector<uint32_t> library;  // the materials in library order
    bool named = false;             // a usemtl named a material of the library
    uint32_t current = 0;           // index into `library`, or the default material
    std::vector<glm::vec3> positions, normals;
    long texcoords = 0;
    std::string_view line;
    std::vector<std::string_view> t;
    size_t lineno = 0;
    std::vector<Corner> poly;
    std::vector<std::array<size_t, 3>> tris;
    // The mesh's vertices are the distinct (position, texture, normal, material) corners, as
    // LumiBench's loader keeps them (Model.cpp l.97-144): a vertex on a material or texture seam
    // is split, and without normals in the file each gets its own smooth normal.
    absl::flat_hash_map<std::array<long, 4>, uint32_t> corner_vertex;
    std::vector<long> vertex_normal;  // per mesh vertex: its normal index, or -1
    std::vector<uint32_t> face_material;
    bool any_default = false;
    while (next_line(data, pos, line)) {
        ++lineno;
        const auto hash = line.find('#');
        if (hash != std::string::npos) line = line.substr(0, hash);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        split(line, t);
        if (t.empty()) continue;
        if (t[0] == "v" || t[0] == "vn") {
            const bool position = t[0] == "v";
            if (t.size() < 4)
                throw input_error(path, lineno, std::string(position ? "vertex" : "normal") + " needs 3 coordinates: '" + std::string(line) + "'");
            glm::vec3 v;
            for (int a = 0; a < 3; ++a) {
                if (!parse_float(t[a + 1], &v[a]))
                    throw input_error(path, lineno, std::string(position ? "bad vertex coordinate '" : "bad normal coordinate '") + std::string(t[a + 1]) + "'");
                check_finite(path, lineno, t[a + 1], v[a]);
            }
            (position ? positions : normals).push_back(v);
        } else if (t[0] == "vt") {
            ++texcoords;
        } else if (t[0] == "f") {
            if (t.size() < 4) throw input_error(path, lineno, "face needs at least 3 vertices: '" + std::string(line) + "'");
            poly.clear();
            for (size_t k = 1; k < t.size(); ++k)
                poly.push_back(parse_corner(t[k], long(positions.size()), texcoords, long(normals.size()), path, lineno));
            const long mat = named ? long(current) : -1;  // -1: the default, resolved at the end
            any_default |= mat < 0;
            triangulate(poly, positions, tinyobj, tris);
            for (const auto& tri : tris) {
                glm::uvec3 idx;
                for (int k = 0; k < 3; ++k) {
                    const Corner& c = poly[tri[k]];
                    const auto [it, fresh] = corner_vertex.try_emplace({c.v, c.vt, c.vn, mat}, uint32_t(mesh.vertices.size()));
                    if (fresh) {
                        mesh.vertices.push_back(positions[size_t(c.v)]);
                        vertex_normal.push_back(c.vn);
                    }
                    idx[k] = it->second;
                }
                mesh.triangles.push_back(idx);
                face_material.push_back(uint32_t(mat < 0 ? ~0u : uint32_t(mat)));
            }
        } else if (t[0] == "usemtl") {
            const auto it = materials.find(t.size() > 1 ? std::string(t[1]) : "");
            named = it != materials.end();
            if (named) current = it->second;
        } else if (t[0] == "mtllib" && t.size() > 1) {
            load_mtl(scene, (fs::path(path).parent_path() / std::string(t[1])).string(), materials, library);
        }
    }
    // Faces before any usemtl, or naming no material of the library, take the library's first
    // material (tinyobjloader's -1, taken as 0 by Model.cpp l.131-134); a file without a library
    // takes the default grey (0.7) Lambertian (l.80-88).
    const uint32_t fallback = !library.empty() ? library.front() : (any_default ? add_material(scene, Material{}) : 0u);
    mesh.file_materials = library.empty() && any_default ? std::vector<uint32_t>{fallback} : library;
    mesh.material.reserve(face_material.size());
    for (uint32_t m : face_material) mesh.material.push_back(m == ~0u ? fallback : m);
    // Normals: the file's; without any (`vn`), smooth normals (compute_smooth_normals), which
    // also stand in for a corner whose normal index is missing or out of range.
    if (!normals.empty()) {
        compute_smooth_normals(mesh);
        for (size_t i = 0; i < mesh.vertices.size(); ++i)
            if (vertex_normal[i] >= 0) mesh.normals[i] = normals[size_t(vertex_normal[i])];
    }
}

// --- PLY -------------------------------------------------------------------------------------

struct PlyProperty {
    std::string name, type, count_type;  // count_type non-empty for lists
};
struct PlyElement {
    std::string name;
    size_t count = 0;
    std::vector<PlyProperty> props;
};

size_t ply_type_size(const std::string& t) {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32") return 4;
    if (t == "double" || t == "float64") return 8;
    return 0;
}

class PlyReader {
public:
    PlyReader(const std::string& path, std::string data) : path_(path), data_(std::move(data)) {}

    void load(Mesh& mesh, uint32_t material) {
        parse_header();
        // Faces may come before the vertices (the format orders elements as the header lists
        // them): their indices are checked against the vertex element's count in the header.
        const size_t base = mesh.vertices.size();
        size_t vertices = 0;
        for (const PlyElement& e : elements_)
            if (e.name == "vertex") vertices += e.count;
        for (const PlyElement& e : elements_) {
            const bool vertex = e.name == "vertex", face = e.name == "face";
            int ix = -1, iy = -1, iz = -1, ilist = -1;
            for (size_t p = 0; p < e.props.size(); ++p) {
                const auto& n = e.props[p].name;
                if (vertex && n == "x") ix = int(p);
                if (vertex && n == "y") iy = int(p);
                if (vertex && n == "z") iz = int(p);
                if (face && (n == "vertex_indices" || n == "vertex_index") && !e.props[p].count_type.empty()) ilist = int(p);
            }
            if (vertex && (ix < 0 || iy < 0 || iz < 0)) throw input_error(path_, 0, "vertex element lacks x, y or z");
            if (face && ilist < 0) throw input_error(path_, 0, "face element lacks a vertex_indices list");
            // Bounded work for bounded input: a record takes at least its values' sizes (binary) or
            // a line of two bytes (ASCII: a character and a newline), so a count the rest of the
            // file cannot hold is refused before any iteration. A binary element without
            // properties holds nothing to read.
            if (!ascii_ && e.props.empty()) continue;
            size_t record_bytes = ascii_ ? 2 : 0;
            if (!ascii_)
                for (const PlyProperty& pr : e.props) record_bytes += ply_type_size(pr.count_type.empty() ? pr.type : pr.count_type);
            const size_t left = data_.size() - std::min(pos_, data_.size());
            if (e.count > (left + 1) / record_bytes)  // + 1: the last line may lack its newline
                fail("element '" + e.name + "' declares " + std::to_string(e.count) + " records, more than the " + std::to_string(left) +
                     " bytes left in the file can hold");
            std::vector<double> list;
            std::vector<uint32_t> poly;
            for (size_t i = 0; i < e.count; ++i) {
                glm::vec3 v(0.0f);
                begin_record();
                for (size_t p = 0; p < e.props.size(); ++p) {
                    const PlyProperty& pr = e.props[p];
                    if (!pr.count_type.empty()) {
                        const double n = read_value(pr.count_type);
                        if (n < 0 || n > 1e6 || n != std::floor(n)) fail("bad list length " + std::to_string(n));
                        list.resize(size_t(n));
                        for (double& x : list) x = read_value(pr.type);
                        if (int(p) == ilist) {
                            if (list.size() < 3) fail("face with fewer than 3 vertices");
                            poly.clear();
                            for (double x : list) {
                                if (x < 0 || x >= double(vertices) || x != std::floor(x))
                                    fail("face index " + std::to_string(x) + " out of range (0.." +
                                         std::to_string(vertices ? vertices - 1 : 0) + ")");
                                poly.push_back(uint32_t(base + size_t(x)));
                            }
                            fan(mesh, poly, material);
                        }
                    } else {
                        const double x = read_value(pr.type);
                        if (int(p) == ix || int(p) == iy || int(p) == iz) {
                            const float f = float(x);
                            if (!std::isfinite(f)) fail("vertex coordinate " + std::to_string(x) + " is not finite (NaN or infinity)");
                            v[int(p) == ix ? 0 : int(p) == iy ? 1 : 2] = f;
                        }
                    }
                }
                end_record();
                if (vertex) mesh.vertices.push_back(v);
            }
        }
    }

private:
    [[noreturn]] void fail(const std::string& msg) const {
        if (ascii_) throw input_error(path_, line_, msg);
        throw input_error(path_, 0, "byte " + std::to_string(pos_) + ": " + msg);
    }

    std::string_view next_line() {
        if (pos_ >= data_.size()) fail("unexpected end of file");
        const size_t nl = data_.find('\n', pos_);
        const size_t end = nl == std::string::npos ? data_.size() : nl;
        std::string_view l = std::string_view(data_).substr(pos_, end - pos_);
        pos_ = end + (nl == std::string::npos ? 0 : 1);
        ++line_;
        if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
        return l;
    }

    void parse_header() {
        if (next_line() != "ply") fail("not a PLY file (first line must be 'ply')");
        for (;;) {
            const auto t = split(next_line());
            if (t.empty() || t[0] == "comment" || t[0] == "obj_info") continue;
            if (t[0] == "end_header") break;
            if (t[0] == "format") {
                if (t.size() < 2) fail("format line incomplete");
                ascii_ = t[1] == "ascii";
                big_endian_ = t[1] == "binary_big_endian";
                if (!ascii_ && !big_endian_ && t[1] != "binary_little_endian") fail("unknown PLY format '" + std::string(t[1]) + "'");
            } else if (t[0] == "element") {
                if (t.size() < 3) fail("element line incomplete");
                PlyElement e;
                e.name = t[1];
                const std::string count(t[2]);
                char* end = nullptr;
                errno = 0;
                e.count = std::strtoull(count.c_str(), &end, 10);
                // strtoull takes "-5" as 2^64 - 5: only digits are a count.
                if (count.empty() || *end || errno == ERANGE || count.find_first_not_of("0123456789") != std::string::npos)
                    fail("bad element count '" + count + "' (a whole number of records)");
                elements_.push_back(e);
            } else if (t[0] == "property") {
                if (elements_.empty()) fail("property before any element");
                PlyProperty p;
                if (t.size() >= 5 && t[1] == "list") {
                    p.count_type = t[2];
                    p.type = t[3];
                    p.name = t[4];
                    if (!ply_type_size(p.count_type)) fail("unknown PLY type '" + p.count_type + "'");
                } else if (t.size() >= 3) {
                    p.type = t[1];
                    p.name = t[2];
                } else {
                    fail("property line incomplete");
                }
                if (!ply_type_size(p.type)) fail("unknown PLY type '" + p.type + "'");
                elements_.back().props.push_back(p);
            } else {
                fail("unexpected header line starting with '" + std::string(t[0]) + "'");
            }
        }
    }

    void begin_record() {
        if (!ascii_) return;
        std::string_view l;
        do {
            l = next_line();
        } while (l.find_first_not_of(" \t") == std::string::npos);
        split(l, tokens_);
        tok_ = 0;
    }
    void end_record() {
        if (ascii_ && tok_ != tokens_.size()) fail("extra values on the line");
    }

    double read_value(const std::string& type) {
        if (ascii_) {
            if (tok_ >= tokens_.size()) fail("too few values on the line");
            const std::string_view s = tokens_[tok_++];
            double v = 0;
            if (!parse_number(s, &v)) fail("bad number '" + std::string(s) + "'");
            return v;
        }
        const size_t n = ply_type_size(type);
        if (pos_ + n > data_.size()) fail("unexpected end of file");
        unsigned char b[8];
        std::memcpy(b, data_.data() + pos_, n);
        pos_ += n;
        if (big_endian_) std::reverse(b, b + n);
        auto as = [&](auto v) { std::memcpy(&v, b, sizeof(v)); return double(v); };
        if (type == "char" || type == "int8") return as(int8_t());
        if (type == "uchar" || type == "uint8") return as(uint8_t());
        if (type == "short" || type == "int16") return as(int16_t());
        if (type == "ushort" || type == "uint16") return as(uint16_t());
        if (type == "int" || type == "int32") return as(int32_t());
        if (type == "uint" || type == "uint32") return as(uint32_t());
        if (type == "float" || type == "float32") return as(float());
        return as(double());
    }

    std::string path_, data_;
    size_t pos_ = 0, line_ = 0;
    bool ascii_ = true, big_endian_ = false;
    std::vector<PlyElement> elements_;
    std::vector<std::string_view> tokens_;  // of the current record's line, in data_
    size_t tok_ = 0;
};

// --- OFF -----------------------------------------------------------------------------------------
// "OFF", then "vertices faces edges" (on the same line or the next), then one line "x y z [...]"
// per vertex and one line "n i_1 .. i_n [colour]" per face; '#' starts a comment. Read here, not
// by Assimp, whose reader clamped out-of-range indices silently and asserted (abort) on malformed
// faces. Faces of fewer than 3 vertices carry no surface and are skipped, as on the Assimp path.
void load_off(Mesh& mesh, uint32_t material, const std::string& path) {
    const std::string data = read_file_maybe_gz(path);
    size_t pos = 0, line_no = 0;
    std::vector<std::string_view> tok;
    const auto next = [&]() {  // the next line with tokens, comments removed
        std::string_view line;
        while (next_line(data, pos, line)) {
            ++line_no;
            split(line.substr(0, line.find('#')), tok);
            if (!tok.empty()) return true;
        }
        return false;
    };
    if (!next() || tok[0] != "OFF")
        throw input_error(path, line_no, "not an OFF file: the first line must be 'OFF' (COFF, NOFF and binary OFF are not read)");
    tok.erase(tok.begin());
    if (tok.empty() && !next()) throw input_error(path, line_no, "the file ends before the counts 'vertices faces edges'");
    long nv = -1, nf = -1;
    if (tok.size() < 2 || !parse_number(tok[0], &nv) || !parse_number(tok[1], &nf) || nv < 0 || nf < 0)
        throw input_error(path, line_no, "bad counts line '" + std::string(tok.empty() ? "" : tok[0]) +
                                             " ...': expected 'vertices faces edges', integers >= 0");
    // Counts checked against the bytes left before anything is reserved: a vertex line takes at
    // least 6 bytes ("0 0 0\n"), a face line at least 2 ("0\n").
    const uint64_t left = data.size() - std::min(pos, data.size());
    if (uint64_t(nv) > left / 6 || uint64_t(nf) > (left - uint64_t(nv) * 6) / 2)
        throw input_error(path, line_no, "declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                                             " faces, more than the " + std::to_string(left) + " bytes left in the file can hold");
    const uint32_t base = uint32_t(mesh.vertices.size());
    mesh.vertices.reserve(base + size_t(nv));
    for (long v = 0; v < nv; ++v) {
        if (!next()) throw input_error(path, line_no, "the file ends after " + std::to_string(v) + " of " + std::to_string(nv) + " vertices");
        if (tok.size() < 3) throw input_error(path, line_no, "a vertex needs 3 coordinates, the line has " + std::to_string(tok.size()));
        glm::vec3 p;
        for (int k = 0; k < 3; ++k) {
            if (!parse_float(tok[size_t(k)], &p[k]))
                throw input_error(path, line_no, "vertex coordinate '" + std::string(tok[size_t(k)]) + "' is not a number");
            check_finite(path, line_no, tok[size_t(k)], p[k]);
        }
        mesh.vertices.push_back(p);
    }
    std::vector<uint32_t> poly;
    for (long f = 0; f < nf; ++f) {
        if (!next()) throw input_error(path, line_no, "the file ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces");
        long n = -1;
        if (!parse_number(tok[0], &n) || n < 0 || uint64_t(n) > tok.size() - 1)
            throw input_error(path, line_no, "face " + std::to_string(f) + ": vertex count '" + std::string(tok[0]) +
                                                 "' is not an integer from 0 to the " + std::to_string(tok.size() - 1) + " indices on the line");
        poly.clear();
        for (long k = 1; k <= n; ++k) {
            long i = -1;
            if (!parse_number(tok[size_t(k)], &i) || i < 0 || i >= nv)
                throw input_error(path, line_no, "face " + std::to_string(f) + ": vertex index '" + std::string(tok[size_t(k)]) +
                                                     "' out of range (0 to " + std::to_string(nv - 1) + ")");
            poly.push_back(base + uint32_t(i));
        }
        if (poly.size() >= 3) fan(mesh, poly, material);
    }
}

// --- Assimp (glTF/GLB and other formats) ---------------------------------------------------------

void load_assimp(Scene& scene, Mesh& mesh, const std::string& path) {
    Assimp::Importer imp;
    const aiScene* sc = imp.ReadFile(path, aiProcess_Triangulate | aiProcess_PreTransformVertices);
    if (!sc) throw input_error(path, 0, std::string("cannot read mesh: ") + imp.GetErrorString());
    std::vector<uint32_t> mat_index(sc->mNumMaterials);
    for (unsigned i = 0; i < sc->mNumMaterials; ++i) {
        Material m;
        aiColor3D c;
        if (sc->mMaterials[i]->Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS) m.albedo = {c.r, c.g, c.b};
        if (sc->mMaterials[i]->Get(AI_MATKEY_COLOR_EMISSIVE, c) == AI_SUCCESS && (c.r > 0 || c.g > 0 || c.b > 0)) {
            m.emission = {c.r, c.g, c.b};
            m.kind = Material::Kind::Emitter;
        }
        mat_index[i] = add_material(scene, m);
    }
    const uint32_t fallback = add_material(scene, Material{});
    for (unsigned mi = 0; mi < sc->mNumMeshes; ++mi) {
        const aiMesh* am = sc->mMeshes[mi];
        const uint32_t base = uint32_t(mesh.vertices.size());
        for (unsigned v = 0; v < am->mNumVertices; ++v) {
            const aiVector3D& p = am->mVertices[v];
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                throw input_error(path, 0, "vertex " + std::to_string(v) + " of mesh " + std::to_string(mi) + " is not finite");
            mesh.vertices.push_back({p.x, p.y, p.z});
        }
        const uint32_t mat = am->mMaterialIndex < mat_index.size() ? mat_index[am->mMaterialIndex] : fallback;
        std::vector<uint32_t> poly;
        for (unsigned f = 0; f < am->mNumFaces; ++f) {
            const aiFace& face = am->mFaces[f];
            if (face.mNumIndices < 3) continue;  // points and lines carry no surface
            poly.assign(face.mIndices, face.mIndices + face.mNumIndices);
            for (uint32_t& i : poly) i += base;
            fan(mesh, poly, mat);
        }
    }
}

// --- Assimp in a child process ------------------------------------------------------------------
// Assimp trusts the sizes a file declares: a 50-byte GLB whose JSON chunk claims 4 GB made it
// allocate 4.2 GB and run for over a minute, and its asserts abort the process. So it runs in a
// forked child with limits on its address space (what the process had at the fork plus 2 GiB plus
// 16 bytes per byte of the file) and CPU time (5 s plus 1 s per MB: an 88-byte ".gltf" holding a
// broken PLY kept Assimp's PLY reader busy until the old limit of 30 s, so a 1 MB input could take
// over 30 s; Assimp reads a real 1 MB glTF in well under a second; ImporterLimits, mesh_io.h);
// the child sends the mesh back through a pipe, and any failure there (an exception, running out
// of memory, an abort, a crash, the CPU limit, twice that in wall time) is an InputError naming
// the file, as is an answer that does not hold together (read_importer_answer). Under
// AddressSanitizer, whose shadow memory takes terabytes of address space, the address-space limit
// is left out.

constexpr uint64_t kImporterExtraBytes = uint64_t(2) << 30;

// GCC says __SANITIZE_ADDRESS__; clang (14) only answers __has_feature.
#if defined(__SANITIZE_ADDRESS__)
#define RTU_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RTU_ADDRESS_SANITIZER 1
#endif
#endif

}  // namespace
}  // namespace rtu
// Present only in sanitizer builds (weak: null otherwise).
extern "C" void __sanitizer_set_death_callback(void (*callback)(void)) __attribute__((weak));
namespace rtu {
namespace {

#ifndef RTU_ADDRESS_SANITIZER
uint64_t address_space_now() {
    std::FILE* f = std::fopen("/proc/self/statm", "r");
    unsigned long pages = 0;
    if (f) {
        if (std::fscanf(f, "%lu", &pages) != 1) pages = 0;
        std::fclose(f);
    }
    return uint64_t(pages) * uint64_t(sysconf(_SC_PAGESIZE));
}
#endif

template <class T>
void put(std::string& out, const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    out.append(reinterpret_cast<const char*>(&v), sizeof v);
}
template <class T>
void put_vector(std::string& out, const std::vector<T>& v) {
    put(out, uint64_t(v.size()));
    if (!v.empty()) out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}
// Reads what put wrote, from the same binary; a short message is the child's fault, reported.
struct Reader {
    const std::string& in;
    size_t pos = 1;  // after the tag
    template <class T>
    T get() {
        T v;
        if (in.size() - pos < sizeof v) throw std::runtime_error("short message");
        std::memcpy(&v, in.data() + pos, sizeof v);
        pos += sizeof v;
        return v;
    }
    template <class T>
    void get_vector(std::vector<T>& v) {
        const uint64_t n = get<uint64_t>();
        if (n > (in.size() - pos) / sizeof(T)) throw std::runtime_error("short message");
        v.resize(size_t(n));
        if (n) std::memcpy(v.data(), in.data() + pos, size_t(n) * sizeof(T));  // data() may be null when empty
        pos += size_t(n) * sizeof(T);
    }
};

// The child's answer: 'M' and the materials and mesh, or 'E' and a message.
std::string import_in_child(const std::string& path) {
    Scene scene;
    Mesh mesh;
    try {
        load_assimp(scene, mesh, path);
    } catch (const std::bad_alloc&) {
        return "E" + path + ": the mesh importer (Assimp) needs more memory than its limit for this file (" +
               std::to_string(kImporterExtraBytes >> 20) + " MiB beyond rtsim's own)";
    } catch (const std::exception& e) {
        return std::string("E") + e.what();
    }
    std::string out = "M";
    put(out, uint64_t(scene.materials.size()));
    for (const Material& m : scene.materials) {  // Assimp's materials carry no name
        put(out, m.kind);
        put(out, m.albedo);
        put(out, m.fuzz);
        put(out, m.ior);
        put(out, m.emission);
    }
    put_vector(out, mesh.vertices);
    put_vector(out, mesh.triangles);
    put_vector(out, mesh.material);
    return out;
}

// A time in seconds as setitimer takes it.
itimerval one_shot(double seconds) {
    itimerval t{};
    t.it_value.tv_sec = time_t(seconds);
    t.it_value.tv_usec = suseconds_t((seconds - double(t.it_value.tv_sec)) * 1e6);
    if (t.it_value.tv_sec == 0 && t.it_value.tv_usec == 0) t.it_value.tv_usec = 1;  // zero would disarm it
    return t;
}

void load_assimp_isolated(Scene& scene, Mesh& mesh, const std::string& path, const ImporterLimits& limits) {
    if (!(limits.cpu_s > 0.0) || !(limits.cpu_s_per_mb >= 0.0) || limits.cpu_s > 1e6 || limits.cpu_s_per_mb > 1e6)
        throw std::invalid_argument("ImporterLimits: cpu_s must be in (0, 1e6], cpu_s_per_mb in [0, 1e6]");
    std::error_code ec;
    const uint64_t file_bytes = fs::file_size(path, ec);
    const double cpu = limits.cpu_s + limits.cpu_s_per_mb * double(ec ? 0 : file_bytes) / double(1 << 20);
    int fd[2];
    if (pipe(fd) != 0) throw input_error(path, 0, std::string("cannot start the mesh importer: ") + std::strerror(errno));
    std::fflush(nullptr);
    const pid_t pid = fork();
    if (pid < 0) {
        close(fd[0]);
        close(fd[1]);
        throw input_error(path, 0, std::string("cannot start the mesh importer: ") + std::strerror(errno));
    }
    if (pid == 0) {  // the child: limits, import, answer, and _exit (no destructors, no atexit)
        close(fd[0]);
        // Die plainly on a fault: a handler inherited from the parent (a fuzzer's or a
        // sanitizer's crash report) would otherwise treat the child's fault as the parent's.
        // The limits' signals are unblocked too, whatever mask the forking thread had.
        sigset_t limits_signals;
        sigemptyset(&limits_signals);
        for (const int sig : {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGXCPU, SIGALRM, SIGPROF}) {
            signal(sig, SIG_DFL);
            sigaddset(&limits_signals, sig);
        }
        sigprocmask(SIG_UNBLOCK, &limits_signals, nullptr);
        if (&__sanitizer_set_death_callback) __sanitizer_set_death_callback(nullptr);  // likewise a fuzzer's death report
#ifndef RTU_ADDRESS_SANITIZER
        const rlim_t as = rlim_t(address_space_now() + kImporterExtraBytes + 16 * (ec ? 0 : file_bytes));
        const rlimit as_limit{as, as};
        setrlimit(RLIMIT_AS, &as_limit);
#endif
        // CPU time: SIGPROF at `cpu` seconds (ITIMER_PROF counts user and system time, to the
        // microsecond), with RLIMIT_CPU a whole second behind it should the timer be lost; wall
        // time: SIGALRM at twice that plus 5 s, should the importer block (on a FIFO it names, say).
        // Timers are not inherited across fork, so the parent's (a fuzzer's -timeout) are untouched.
        const itimerval prof = one_shot(cpu), wall = one_shot(2 * cpu + 5);
        setitimer(ITIMER_PROF, &prof, nullptr);
        const rlim_t cpu_backstop = rlim_t(std::ceil(cpu)) + 1;
        const rlimit cpu_limit{cpu_backstop, cpu_backstop + 1};
        setrlimit(RLIMIT_CPU, &cpu_limit);
        setitimer(ITIMER_REAL, &wall, nullptr);
        const std::string out = import_in_child(path);
        for (size_t done = 0; done < out.size();) {
            const ssize_t n = write(fd[1], out.data() + done, out.size() - done);
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) _exit(1);
            done += size_t(n);
        }
        _exit(0);
    }
    close(fd[1]);
    std::string in;
    char buf[1 << 16];
    for (;;) {
        const ssize_t n = read(fd[0], buf, sizeof buf);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;
        in.append(buf, size_t(n));
    }
    close(fd[0]);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    read_importer_answer(scene, mesh, path, in, status);
}

}  // namespace

void read_importer_answer(Scene& scene, Mesh& mesh, const std::string& path, const std::string& in, int status) {
    if (WIFSIGNALED(status)) {
        const int sig = WTERMSIG(status);
        const char* why = sig == SIGABRT                                     ? " (an assertion inside Assimp)"
                          : sig == SIGXCPU || sig == SIGPROF || sig == SIGKILL ? " (more CPU time than its limit for this file)"
                          : sig == SIGALRM                                   ? " (more wall time than its limit for this file)"
                          : sig == SIGSEGV                                   ? " (a crash inside Assimp, or its memory limit)"
                                                                             : "";
        throw input_error(path, 0, "the mesh importer (Assimp) died on this file: signal " + std::to_string(sig) + why);
    }
    // The child writes its whole answer and then exits 0; anything else is an answer cut short.
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || in.empty() || (in[0] != 'M' && in[0] != 'E'))
        throw input_error(path, 0, "the mesh importer (Assimp) ended without an answer (exit status " +
                                       std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")");
    if (in[0] == 'E') throw InputError(in.substr(1));
    const auto broken = [&path](const std::string& what) {
        return input_error(path, 0, "the mesh importer (Assimp) sent back a broken answer (" + what + ")");
    };
    const auto finite3 = [](const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
    Mesh got;
    std::vector<Material> materials;
    try {
        Reader r{in};
        const uint64_t n_materials = r.get<uint64_t>();
        for (uint64_t i = 0; i < n_materials; ++i) {  // each one reads bytes, so a huge count ends as a short message
            Material m;
            const auto kind = r.get<uint8_t>();
            if (kind > uint8_t(Material::Kind::Emitter)) throw broken("material kind " + std::to_string(kind));
            m.kind = Material::Kind(kind);
            m.albedo = r.get<glm::vec3>();
            m.fuzz = r.get<float>();
            m.ior = r.get<float>();
            m.emission = r.get<glm::vec3>();
            if (!finite3(m.albedo) || !finite3(m.emission) || !std::isfinite(m.fuzz) || !std::isfinite(m.ior))
                throw broken("a material's number is not finite");
            materials.push_back(m);
        }
        r.get_vector(got.vertices);
        r.get_vector(got.triangles);
        r.get_vector(got.material);
        if (r.pos != in.size()) throw broken(std::to_string(in.size() - r.pos) + " bytes after its end");
    } catch (const InputError&) {
        throw;  // broken(...) above
    } catch (const std::runtime_error& e) {
        throw broken(e.what());  // the Reader's "short message"
    }
    for (size_t v = 0; v < got.vertices.size(); ++v)
        if (!finite3(got.vertices[v])) throw broken("vertex " + std::to_string(v) + " is not finite");
    if (got.material.size() != got.triangles.size())
        throw broken(std::to_string(got.triangles.size()) + " triangles but " + std::to_string(got.material.size()) + " materials");
    for (const glm::uvec3& t : got.triangles)
        if (t.x >= got.vertices.size() || t.y >= got.vertices.size() || t.z >= got.vertices.size())
            throw broken("a triangle's vertex index out of range");
    for (const uint32_t m : got.material)
        if (m >= materials.size()) throw broken("a triangle's material index out of range");
    // Accepted whole: only now does anything reach the caller's scene.
    const uint32_t base = uint32_t(scene.materials.size());
    for (Material& m : materials) add_material(scene, std::move(m));
    for (uint32_t& m : got.material) m += base;
    mesh.vertices = std::move(got.vertices);
    mesh.triangles = std::move(got.triangles);
    mesh.material = std::move(got.material);
}

bool is_mesh_file(const std::string& path) {
    const std::string ext = mesh_extension(path);
    if (ext == "obj" || ext == "ply") return true;
    const std::string name = lower(path);
    const bool gz = name.size() > 3 && name.compare(name.size() - 3, 3, ".gz") == 0;
    if (ext.empty() || gz) return false;  // only OBJ and PLY are read through zlib
    Assimp::Importer imp;
    return imp.IsExtensionSupported("." + ext);
}

uint32_t load_mesh_file(Scene& scene, const std::string& path, const ImporterLimits& limits, bool tinyobj) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw input_error(path, 0, "file not found");
    // A FIFO, socket or device would block the reader (Assimp waits forever on a FIFO) or never end.
    if (!fs::is_regular_file(path, ec))
        throw input_error(path, 0, "not a regular file (a mesh is read from a file, not a FIFO, socket or device)");
    if (!is_mesh_file(path))
        throw input_error(path, 0, "unknown mesh format '" + mesh_extension(path) +
                                       "' (allowed: .obj, .ply, optionally .gz; .gltf, .glb, .off and other Assimp formats)");
    Mesh mesh;
    mesh.name = path;
    const std::string ext = mesh_extension(path);
    if (ext == "obj") {
        load_obj(scene, mesh, path, tinyobj);
    } else if (ext == "ply") {
        const uint32_t mat = add_material(scene, Material{});
        PlyReader(path, read_file_maybe_gz(path)).load(mesh, mat);
    } else if (ext == "off") {
        load_off(mesh, add_material(scene, Material{}), path);
    } else {
        load_assimp_isolated(scene, mesh, path, limits);
    }
    if (mesh.normals.empty()) compute_smooth_normals(mesh);
    scene.meshes.push_back(std::move(mesh));
    return uint32_t(scene.meshes.size() - 1);
}

}  // namespace rtu
