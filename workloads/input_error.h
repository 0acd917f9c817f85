// Bad user input (file, line, value): rtsim reports the message and exits with status 2.
#pragma once
#include <stdexcept>
#include <string>

namespace rtu {

struct InputError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// "FILE:LINE: message" (LINE omitted when 0).
inline InputError input_error(const std::string& file, size_t line, const std::string& msg) {
    return InputError(file + (line ? ":" + std::to_string(line) : std::string()) + ": " + msg);
}

}  // namespace rtu
