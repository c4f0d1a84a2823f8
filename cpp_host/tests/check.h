// Tiny assertion harness for the mfhost tests: CHECK records a failure and continues;
// main returns the failure count (non-zero = test failed). Prints "N passed, N failed".
#pragma once

#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

namespace check {

inline int& failures() { static int f = 0; return f; }
inline int& passes() { static int p = 0; return p; }

inline void report(bool ok, const char* expr, const char* file, int line, const std::string& extra = std::string()) {
    if (ok) {
        ++passes();
        return;
    }
    ++failures();
    std::fprintf(stderr, "%s:%d: CHECK failed: %s %s\n", file, line, expr, extra.c_str());
}

struct Case {
    const char* name;
    std::function<void()> fn;
};
inline std::vector<Case>& cases() { static std::vector<Case> c; return c; }
struct Register {
    Register(const char* n, std::function<void()> f) { cases().push_back({n, std::move(f)}); }
};

inline int run_all() {
    for (const Case& c : cases()) {
        int before = failures();
        try {
            c.fn();
        } catch (const std::exception& e) {
            ++failures();
            std::fprintf(stderr, "[%s] unexpected exception: %s\n", c.name, e.what());
        }
        std::printf("[%s] %s\n", failures() == before ? " OK " : "FAIL", c.name);
    }
    std::printf("%d passed, %d failed\n", passes(), failures());
    return failures() == 0 ? 0 : 1;
}

}  // namespace check

#define CHECK(cond) ::check::report(bool(cond), #cond, __FILE__, __LINE__)
#define CHECK_MSG(cond, msg) ::check::report(bool(cond), #cond, __FILE__, __LINE__, (msg))
#define CHECK_NEAR(a, b, tol)                                                                            \
    do {                                                                                                 \
        double _a = double(a), _b = double(b), _t = double(tol);                                         \
        ::check::report(std::fabs(_a - _b) <= _t, #a " ~= " #b, __FILE__, __LINE__,                      \
                        "(" + std::to_string(_a) + " vs " + std::to_string(_b) + ", tol " + std::to_string(_t) + ")"); \
    } while (0)
#define CHECK_THROWS_WITH(stmt, substr)                                                                  \
    do {                                                                                                 \
        std::string _msg;                                                                                \
        bool _threw = false;                                                                             \
        try {                                                                                            \
            stmt;                                                                                        \
        } catch (const std::exception& _e) {                                                             \
            _threw = true;                                                                               \
            _msg = _e.what();                                                                            \
        }                                                                                                \
        ::check::report(_threw && _msg.find(substr) != std::string::npos, #stmt " throws \"" substr "\"", \
                        __FILE__, __LINE__, "(got: " + (_threw ? _msg : std::string("no exception")) + ")"); \
    } while (0)
#define TEST_CASE(name)                                              \
    static void name();                                              \
    static ::check::Register name##_reg(#name, name);                \
    static void name()
#define TEST_MAIN() \
    int main() { return ::check::run_all(); }
