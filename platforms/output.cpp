#include "output.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <stb/stb_image_write.h>

#include "workloads/input_error.h"

namespace rtu {

namespace {
// The folder a relative or absolute file path is written into.
std::filesystem::path folder_of(const std::filesystem::path& target) {
    return target.has_parent_path() ? target.parent_path() : std::filesystem::path(".");
}

// Writes all of `content` to `fd` and closes it; on failure closes it and returns the errno
// (ENOSPC for a write that took nothing), else 0.
int write_all_and_close(int fd, const std::string& content) {
    for (size_t done = 0; done < content.size();) {
        const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
        if (n <= 0) {
            const int err = n < 0 ? errno : ENOSPC;
            ::close(fd);
            return err;
        }
        done += size_t(n);
    }
    return ::close(fd) != 0 ? errno : 0;
}
}  // namespace

bool is_special_file(const std::string& path) {
    std::error_code ec;
    const std::filesystem::file_status st = std::filesystem::status(path, ec);  // follows links
    return std::filesystem::exists(st) && !std::filesystem::is_regular_file(st) && !std::filesystem::is_directory(st);
}

void check_writable_folder(const std::string& option, const std::string& path) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    const fs::path dir = folder_of(target);
    std::error_code ec;
    // A FIFO or a device (/dev/null) is written into, not replaced: its own permission counts.
    if (is_special_file(path)) {
        if (::access(path.c_str(), W_OK) != 0) throw InputError(option + " " + path + ": cannot write: " + std::strerror(errno));
        return;
    }
    if (!fs::is_directory(dir, ec))
        throw InputError(option + " " + path + ": the folder " + dir.string() + " does not exist (rtsim makes no folders)");
    if (::access(dir.c_str(), W_OK) != 0)
        throw InputError(option + " " + path + ": cannot write in " + dir.string() + ": " + std::strerror(errno));
    if (fs::is_directory(target, ec)) throw InputError(option + " " + path + ": is a folder, not a file");
    if (fs::is_symlink(fs::symlink_status(target, ec)) && !fs::exists(fs::status(target, ec)))
        throw InputError(option + " " + path + ": a symbolic link that loops or leads nowhere (rtsim writes through a link, never over it)");
}

namespace {
// Writes `content` to a new temporary file beside `path` and returns its name; InputError
// naming `path` (and no temporary left) if any write fails.
std::string write_temporary(const std::string& path, const std::string& content) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    const fs::path dir = folder_of(target);
    std::string tmpl = (dir / ("." + target.filename().string() + ".tmp.XXXXXX")).string();
    const int fd = mkstemp(tmpl.data());
    if (fd < 0) throw input_error(path, 0, std::string("cannot write: ") + std::strerror(errno));
    fchmod(fd, 0644);
    if (const int err = write_all_and_close(fd, content)) {
        ::unlink(tmpl.c_str());
        throw input_error(path, 0, std::string("cannot write: ") + std::strerror(err));
    }
    return tmpl;
}

// Where an output goes: through a link to the file it names (the link stays), and into a FIFO, a
// device or a socket directly (/dev/null, a pipe), never replacing it with a regular file.
struct Destination {
    std::string file;
    bool special = false;
};
Destination destination(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (is_special_file(path)) return {path, true};
    if (fs::is_symlink(fs::symlink_status(path, ec))) {
        const fs::path real = fs::canonical(path, ec);
        if (ec) throw input_error(path, 0, "a symbolic link that loops or leads nowhere (rtsim writes through a link, never over it)");
        return {real.string(), false};
    }
    return {path, false};
}

void write_into(const std::string& path, const std::string& content) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) throw input_error(path, 0, std::string("cannot write: ") + std::strerror(errno));
    if (const int err = write_all_and_close(fd, content)) throw input_error(path, 0, std::string("cannot write: ") + std::strerror(err));
}

std::string read_whole(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}
}  // namespace

OutputFiles::~OutputFiles() {
    for (const auto& [temporary, target] : staged_) ::unlink(temporary.c_str());
    for (const auto& [temporary, target] : adopted_special_) ::unlink(temporary.c_str());
}

void OutputFiles::stage(const std::string& path, const std::string& content) {
    try {
        const Destination d = destination(path);
        if (d.special)
            special_.emplace_back(d.file, content);
        else
            staged_.emplace_back(write_temporary(d.file, content), d.file);
    } catch (...) {
        for (const auto& [temporary, target] : staged_) ::unlink(temporary.c_str());
        staged_.clear();
        throw;
    }
}

void OutputFiles::adopt(const std::string& temporary, const std::string& path) {
    const Destination d = destination(path);
    if (d.special)
        adopted_special_.emplace_back(temporary, d.file);
    else
        staged_.emplace_back(temporary, d.file);
}

void OutputFiles::commit() {
    while (!staged_.empty()) {
        const auto [temporary, target] = staged_.front();
        if (std::rename(temporary.c_str(), target.c_str()) != 0) {
            const int err = errno;
            if (err != EXDEV) throw input_error(target, 0, std::string("cannot write: ") + std::strerror(err));  // the destructor removes the rest
            // An adopted file beside a link whose target is on another filesystem: copied there
            // whole first, then renamed.
            const std::string copy = write_temporary(target, read_whole(temporary));
            ::unlink(temporary.c_str());
            staged_.front().first = copy;
            continue;
        }
        staged_.erase(staged_.begin());
    }
    // Special files last: what is written into them cannot be taken back.
    for (const auto& [file, content] : special_) write_into(file, content);
    special_.clear();
    while (!adopted_special_.empty()) {
        const auto [temporary, target] = adopted_special_.front();
        write_into(target, read_whole(temporary));
        ::unlink(temporary.c_str());
        adopted_special_.erase(adopted_special_.begin());
    }
}

void write_file_atomic(const std::string& path, const std::string& content) {
    OutputFiles out;
    out.stage(path, content);
    out.commit();
}

std::string png_bytes(int width, int height, const std::vector<glm::vec3>& rgb) {
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
    return png;
}

void write_png_atomic(const std::string& path, int width, int height, const std::vector<glm::vec3>& rgb) {
    const std::string png = png_bytes(width, height, rgb);
    if (png.empty()) throw input_error(path, 0, "PNG encoding failed");
    write_file_atomic(path, png);
}

std::string temporary_beside(const std::string& path) {
    const std::filesystem::path target(path);
    return (folder_of(target) / ("." + target.filename().string() + ".tmp." + std::to_string(::getpid()))).string();
}

void check_written_whole(const std::string& written, const std::string& target) {
    std::error_code ec;
    const uintmax_t size = std::filesystem::file_size(written, ec);
    struct rlimit limit {};
    if (!ec && ::getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY && size >= limit.rlim_cur)
        throw input_error(target, 0, "cannot write: the file reached the size limit (ulimit -f), so it is cut");
    struct statvfs fs {};
    if (::statvfs(folder_of(std::filesystem::path(written)).c_str(), &fs) != 0) return;
    // Root may write into the blocks reserved for it (f_bfree); others only into f_bavail.
    const unsigned long long left = ::geteuid() == 0 ? fs.f_bfree : fs.f_bavail;
    if (left == 0) throw input_error(target, 0, "cannot write: the filesystem is full, so the file may be cut");
}

}  // namespace rtu
