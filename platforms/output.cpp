#include "output.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sys/stat.h>
#include <unistd.h>

#include <stb/stb_image_write.h>

#include "workloads/input_error.h"

namespace rtu {

namespace {
// The folder a relative or absolute file path is written into.
std::filesystem::path folder_of(const std::filesystem::path& target) {
    return target.has_parent_path() ? target.parent_path() : std::filesystem::path(".");
}
}  // namespace

void check_writable_folder(const std::string& option, const std::string& path) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    const fs::path dir = folder_of(target);
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
        throw InputError(option + " " + path + ": the folder " + dir.string() + " does not exist (rtsim makes no folders)");
    if (::access(dir.c_str(), W_OK) != 0)
        throw InputError(option + " " + path + ": cannot write in " + dir.string() + ": " + std::strerror(errno));
    if (fs::is_directory(target, ec)) throw InputError(option + " " + path + ": is a folder, not a file");
}

void write_file_atomic(const std::string& path, const std::string& content) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    const fs::path dir = folder_of(target);
    std::string tmpl = (dir / ("." + target.filename().string() + ".tmp.XXXXXX")).string();
    const int fd = mkstemp(tmpl.data());
    if (fd < 0) throw input_error(path, 0, std::string("cannot write: ") + std::strerror(errno));
    size_t done = 0;
    while (done < content.size()) {
        const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
        if (n <= 0) {
            const int err = errno;
            ::close(fd);
            ::unlink(tmpl.c_str());
            throw input_error(path, 0, std::string("cannot write: ") + std::strerror(err));
        }
        done += size_t(n);
    }
    fchmod(fd, 0644);
    if (::close(fd) != 0 || std::rename(tmpl.c_str(), path.c_str()) != 0) {
        const int err = errno;
        ::unlink(tmpl.c_str());
        throw input_error(path, 0, std::string("cannot write: ") + std::strerror(err));
    }
}

void write_png_atomic(const std::string& path, int width, int height, const std::vector<glm::vec3>& rgb) {
    std::vector<unsigned char> px(size_t(width) * height * 3);
    for (size_t i = 0; i < size_t(width) * height; ++i)
        for (int c = 0; c < 3; ++c) {
            const float v = std::pow(std::clamp(rgb[i][c], 0.0f, 1.0f), 1.0f / 2.2f);
            px[3 * i + c] = static_cast<unsigned char>(std::lround(v * 255.0f));
        }
    std::string png;
    stbi_write_png_to_func(
        [](void* ctx, void* data, int size) { static_cast<std::string*>(ctx)->append(static_cast<char*>(data), size_t(size)); },
        &png, width, height, 3, px.data(), width * 3);
    if (png.empty()) throw input_error(path, 0, "PNG encoding failed");
    write_file_atomic(path, png);
}

}  // namespace rtu
