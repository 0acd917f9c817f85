#include "file_io.h"

#include <cerrno>
#include <cstring>
#include <filesystem>

#include <zlib.h>

#include "input_error.h"

namespace rtu {

namespace fs = std::filesystem;

std::string read_file_maybe_gz(const std::string& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw input_error(path, 0, "file not found");
    if (!fs::is_regular_file(path, ec)) throw input_error(path, 0, "not a regular file");
    gzFile f = gzopen(path.c_str(), "rb");  // reads plain files unchanged
    if (!f) throw input_error(path, 0, std::string("cannot open: ") + std::strerror(errno));
    // A gzip stream may expand up to 1032 times (deflate's limit), and further in concatenated
    // members: a 1 MB file of zeros took 2.1 GB and 18 s (issue 16). Meshes compress 1.5-10
    // times, so a stream that expands past 64 times its size plus 64 MiB is refused as a bomb
    // (a 1 MB file stops at 128 MiB).
    const uint64_t compressed = fs::file_size(path, ec);
    const uint64_t cap = ec ? ~0ull : 64 * compressed + (64ull << 20);
    std::string out;
    char buf[1 << 16];
    int n;
    while ((n = gzread(f, buf, sizeof buf)) > 0) {
        out.append(buf, size_t(n));
        if (!gzdirect(f) && out.size() > cap) {
            gzclose(f);
            throw input_error(path, 0, "decompresses to more than " + std::to_string(cap >> 20) +
                                           " MiB (64 x its " + std::to_string(compressed) +
                                           " bytes + 64 MiB; meshes compress 1.5-10 x): refused as a decompression bomb; if it is a "
                                           "real mesh, gunzip it first");
        }
    }
    int err = Z_OK;
    const char* msg = gzerror(f, &err);
    const bool bad = n < 0 || (err != Z_OK && err != Z_STREAM_END);
    const std::string why = bad ? std::string(msg ? msg : "read error") : std::string();
    gzclose(f);
    if (bad) throw input_error(path, 0, "cannot read (corrupt gzip?): " + why);
    return out;
}

}  // namespace rtu
