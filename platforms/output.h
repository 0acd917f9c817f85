// Output files are written whole or not at all: content goes to a temporary file beside the
// target, which is renamed over it only when complete.
#pragma once
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace rtu {

// Throws InputError naming the option and path unless the path's folder exists, is a folder and
// is writable, and the path itself is not a folder: checked before a run, so that a bad output
// path does not wait for the simulation.
void check_writable_folder(const std::string& option, const std::string& path);
// Throws InputError naming the path if it cannot be written.
void write_file_atomic(const std::string& path, const std::string& content);
// Linear RGB, row-major from the top row; tone-mapped (clamp, gamma 2.2) to 8-bit PNG.
void write_png_atomic(const std::string& path, int width, int height, const std::vector<glm::vec3>& rgb);

}  // namespace rtu
