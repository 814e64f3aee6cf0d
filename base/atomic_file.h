#pragma once
// Output files are written to a temporary name in the same directory and
// renamed into place, so a failure never leaves a half-written file.
#include <functional>
#include <ostream>
#include <stdexcept>
#include <string>

namespace raylab {

class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Calls write(stream) on a temporary file next to `path`, then renames it to
// `path`. The directory must exist (none is created). On any failure (including an
// exception from write) the temporary file is removed and OutputError thrown.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

// Convenience for a byte buffer.
void write_file_atomically(const std::string& path, const std::string& bytes);

}  // namespace raylab
