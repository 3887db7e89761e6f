#pragma once
/// The project's error types. Libraries throw; only apps/ turns errors into exit codes
/// (InputError → 2, everything else → 1).

#include <stdexcept>
#include <string>

namespace isochart {

/// Base class of every error isocharts throws on purpose.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad input: a missing or malformed file, an invalid mesh, or an invalid option. `what()`
/// is the message without the file; `file()` names the culprit (may be empty for options).
class InputError : public Error {
 public:
  InputError(std::string file, const std::string& message)
      : Error(message), file_(std::move(file)) {}
  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

/// The progress callback asked to stop.
class Cancelled : public Error {
 public:
  Cancelled() : Error("cancelled") {}
};

}  // namespace isochart
