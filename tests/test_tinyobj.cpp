// rtunit reads LumiBench's own scenes as LumiBench's loader does (workloads/mesh_io.cpp); here
// against that loader itself, tinyobjloader 2.0.0rc10 (Debian's libtinyobjloader, the one the
// reference simulator's LumiBench links, ../shared/reference/vulkan-sim.md): every triangle of
// every OBJ file of the shared scenes, in order, by its corners' positions.
#include <gtest/gtest.h>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "workloads/mesh_io.h"
#include "workloads/scene.h"
#include "test_util.h"

namespace fs = std::filesystem;
using namespace rtu;

namespace {

// The corners of every triangle, as LumiBench's Model::LoadModel takes them: the shapes of the
// file in order, each shape's triangulated faces in order (Model.cpp l.97-144).
std::vector<glm::vec3> tinyobj_corners(const std::string& path) {
    tinyobj::ObjReader reader;  // the default configuration, as Model.cpp l.52 uses it
    if (!reader.ParseFromFile(path)) ADD_FAILURE() << path << ": tinyobjloader: " << reader.Error();
    const auto& v = reader.GetAttrib().vertices;
    std::vector<glm::vec3> out;
    for (const auto& shape : reader.GetShapes())
        for (const auto& ix : shape.mesh.indices) out.emplace_back(v[3 * size_t(ix.vertex_index)], v[3 * size_t(ix.vertex_index) + 1], v[3 * size_t(ix.vertex_index) + 2]);
    return out;
}

std::vector<glm::vec3> rtunit_corners(const std::string& path) {
    Scene s;
    load_mesh_file(s, path, {}, true);
    std::vector<glm::vec3> out;
    for (const auto& t : s.meshes[0].triangles)
        for (int k = 0; k < 3; ++k) out.push_back(s.meshes[0].vertices[t[k]]);
    return out;
}

}  // namespace

// PARTY has 12,143 polygons of five to 33 corners, BATH 47, SPRNG 8; the rest are triangles and
// quads. A polygon tinyobjloader gives up on loses its triangles on both sides (9,845 on PARTY).
TEST(Tinyobj, SharedScenesTriangulateAsLumiBenchsLoader) {
    RTU_NEED_SHARED_SCENES();
    // Under the sanitizers, the two smallest (3 of the 137 MB; 26 s there otherwise): every file
    // goes through the same reader, and fuzz_mesh feeds it malformed ones.
    const std::vector<std::string> scenes = rtu::test::kSanitized ? std::vector<std::string>{"ship", "bunny"}
                                                                  : std::vector<std::string>{"party", "bath", "sprng", "ship", "bunny"};
    for (const std::string& scene : scenes) {
        std::vector<std::string> files;
        for (const auto& e : fs::directory_iterator(rtu::test::shared_dir() + "/scenes/" + scene))
            if (e.path().extension() == ".obj") files.push_back(e.path().string());
        std::sort(files.begin(), files.end());
        ASSERT_FALSE(files.empty()) << scene;
        size_t triangles = 0, differ = 0;
        for (const auto& f : files) {
            const auto theirs = tinyobj_corners(f), ours = rtunit_corners(f);
            triangles += ours.size() / 3;
            if (theirs != ours) {
                ++differ;
                ADD_FAILURE() << f << ": " << ours.size() / 3 << " triangles here, " << theirs.size() / 3 << " from tinyobjloader"
                              << (ours.size() == theirs.size() ? " (other corners or order)" : "");
            }
        }
        EXPECT_EQ(differ, 0u) << scene << ": " << files.size() << " files, " << triangles << " triangles";
        EXPECT_GT(triangles, 0u) << scene;
    }
}
