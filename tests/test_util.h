// Small helpers shared by the tests: a temporary folder and file writers.
#pragma once
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include <zlib.h>

namespace rtu::test {

class TempDir {
public:
    TempDir() {
        std::string tmpl = (std::filesystem::temp_directory_path() / "rtunit-test-XXXXXX").string();
        if (!mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
        path_ = tmpl;
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    std::string file(const std::string& name) const { return (path_ / name).string(); }
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

inline std::string write_text(const std::string& path, const std::string& content) {
    std::ofstream(path, std::ios::binary) << content;
    return path;
}

inline std::string write_gz(const std::string& path, const std::string& content) {
    gzFile f = gzopen(path.c_str(), "wb");
    gzwrite(f, content.data(), unsigned(content.size()));
    gzclose(f);
    return path;
}

inline std::string read_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

inline std::string shared_dir() { return RTU_SHARED_DIR; }

// Built with sanitizers (RTU_SANITIZE: scripts/test_sanitizers.sh), where rtsim runs 10-30 times
// slower: the longest tests check a smaller frame or fewer of their cases there, each saying
// which; the Release suite runs them all. CI has to stay within its budget (.ci/run).
#ifndef RTU_SANITIZED
#define RTU_SANITIZED 0
#endif
inline constexpr bool kSanitized = RTU_SANITIZED;

// The real scenes of ../shared/scenes are optional: a test that needs them skips, saying so,
// where they are absent (the built-in scenes need nothing).
inline bool shared_scenes_present() { return std::filesystem::is_directory(shared_dir() + "/scenes/bunny"); }
#define RTU_NEED_SHARED_SCENES()                                                                          \
    do {                                                                                                  \
        if (!rtu::test::shared_scenes_present())                                                          \
            GTEST_SKIP() << "needs the shared scenes in " << rtu::test::shared_dir() << "/scenes, absent here"; \
    } while (0)

}  // namespace rtu::test
