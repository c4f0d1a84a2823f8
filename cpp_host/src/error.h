// mfhost — error reporting. Every user-facing failure is a mf::Error carrying, where known, the
// scene file and line it originates from; main() prints it as one line and exits non-zero.
#pragma once

#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

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

/// Several independent problems found in one run (the scene reader and builder report every
/// refusal of a file at once). what() is the messages, one per line.
class ErrorList : public Error {
public:
    explicit ErrorList(std::vector<Error> errors) : Error(join(errors)), errors_(std::move(errors)) {}
    const std::vector<Error>& errors() const { return errors_; }

private:
    static std::string join(const std::vector<Error>& errors) {
        std::string s;
        for (const Error& e : errors) s += (s.empty() ? "" : "\n") + std::string(e.what());
        return s;
    }
    std::vector<Error> errors_;
};

/// Collects errors up to a bound; `raise()` throws them as one ErrorList (nothing if none).
class ErrorSink {
public:
    static constexpr size_t kMaxErrors = 100;  // a broken file must not flood the terminal
    void add(const Error& e) {
        if (auto* list = dynamic_cast<const ErrorList*>(&e)) {
            for (const Error& x : list->errors()) add(x);
            return;
        }
        if (errors_.size() < kMaxErrors) errors_.push_back(e);
        else ++dropped_;
    }
    bool empty() const { return errors_.empty(); }
    size_t size() const { return errors_.size() + dropped_; }
    void raise() const {
        if (errors_.empty()) return;
        std::vector<Error> all = errors_;
        if (dropped_) all.push_back(Error("... and " + std::to_string(dropped_) + " more problems"));
        if (all.size() == 1) throw all[0];
        throw ErrorList(std::move(all));
    }

private:
    std::vector<Error> errors_;
    size_t dropped_ = 0;
};

/// A number for a message: 6 significant digits ("0.3", "1e-05", "nan").
inline std::string number_str(double v) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%.6g", v);
    return buf;
}

/// A user-supplied string for a message: quoted, and cut to `max_chars` (with its full length)
/// so that a huge attribute is never echoed whole.
inline std::string quote(const std::string& s, size_t max_chars = 64) {
    if (s.size() <= max_chars) return "\"" + s + "\"";
    return "\"" + s.substr(0, max_chars) + "...\" (" + std::to_string(s.size()) + " bytes)";
}

}  // namespace mf
