// Output files are written whole or not at all: content goes to a temporary file beside the
// target, which is renamed over it only when complete; a run's outputs together (OutputFiles).
#pragma once
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace rtu {

// Throws InputError naming the option and path unless the path's folder exists, is a folder and
// is writable, and the path itself is not a folder: checked before a run, so that a bad output
// path does not wait for the simulation.
void check_writable_folder(const std::string& option, const std::string& path);
// Whether `path` (following links) is a FIFO, a device or a socket: an output written into, never
// replaced.
bool is_special_file(const std::string& path);
// Throws InputError naming the path if it cannot be written.
void write_file_atomic(const std::string& path, const std::string& content);
// Linear RGB, row-major from the top row; tone-mapped (clamp, gamma 2.2) to 8-bit PNG.
std::string png_bytes(int width, int height, const std::vector<glm::vec3>& rgb);
void write_png_atomic(const std::string& path, int width, int height, const std::vector<glm::vec3>& rgb);

// A run's outputs, all or none. stage() writes each whole to a temporary file beside its target
// (through a symbolic link, beside the file it names: the link stays; into a FIFO or a device
// such as /dev/null, directly and last, at commit(), since such a file cannot be replaced);
// adopt() takes a file the run wrote itself under a temporary name (the VCD); commit() renames
// them over their targets once every one is written. If staging fails, or the object goes before
// commit(), every temporary is removed: a failed run leaves none of its outputs. (The renames
// stay in folders checked before the run, so they fail only if a folder changes under the run;
// then the error names the file, and the outputs renamed before it stay.)
class OutputFiles {
public:
    OutputFiles() = default;
    OutputFiles(const OutputFiles&) = delete;
    OutputFiles& operator=(const OutputFiles&) = delete;
    ~OutputFiles();
    void stage(const std::string& path, const std::string& content);
    void adopt(const std::string& temporary, const std::string& path);
    void commit();

private:
    std::vector<std::pair<std::string, std::string>> staged_;           // (temporary, target)
    std::vector<std::pair<std::string, std::string>> special_;          // (FIFO or device, content)
    std::vector<std::pair<std::string, std::string>> adopted_special_;  // (temporary, FIFO or device)
};

// A name for a temporary file beside `path` (hidden, with the process id), for a file written by
// other means and adopted later.
std::string temporary_beside(const std::string& path);
// For a file written through a library that does not report failed writes (SystemC's VCD):
// throws InputError naming `target` if `written` may be cut, that is if it reached the process's
// file-size limit (ulimit -f) or its filesystem has no block left for this process.
void check_written_whole(const std::string& written, const std::string& target);

}  // namespace rtu
