// mfhost — error reporting. Every user-facing failure is a mf::Error carrying, where known, the
// scene file and line it originates from; main() prints it as one line and exits non-zero.
#pragma once

#include <stdexcept>
#include <string>

namespace mf {

struct SourceLoc {
    std::string file;  // path as given (empty when unknown)
    int line = 0;      // 1-based; 0 when unknown
    std::string str() const {
        if (file.empty()) return std::string();
        return line > 0 ? file + ":" + std::to_string(line) : file;
    }
};

class Error : public std::runtime_error {
public:
    explicit Error(const std::string& msg) : std::runtime_error(msg) {}
    Error(const SourceLoc& loc, const std::string& msg)
        : std::runtime_error(loc.file.empty() ? msg : loc.str() + ": " + msg), loc_(loc) {}
    const SourceLoc& loc() const { return loc_; }

private:
    SourceLoc loc_;
};

}  // namespace mf
