// Three tiers of errors (see docs/user/errors.md):
//  1. UserError: bad input (scene file, command line, output folder). Carries file:line and key and is
//     printed as "file:line: key: what is wrong; what is allowed". The CLI exits with code 2.
//  2. TPB_CHECK: invariants of the code. A failure is a bug: prints the condition and aborts.
//  3. Counted warnings: rejected NaN/Inf samples, energy outside the film... are counted in stats.
#pragma once
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace tpb {

class UserError : public std::runtime_error {
public:
    UserError(std::string file, int line, std::string key, const std::string& message)
        : std::runtime_error(format(file, line, key, message)),
          file_(std::move(file)),
          line_(line),
          key_(std::move(key)) {}
    explicit UserError(const std::string& message) : std::runtime_error(message), line_(0) {}

    const std::string& file() const { return file_; }
    int line() const { return line_; }
    const std::string& key() const { return key_; }

private:
    static std::string format(const std::string& file, int line, const std::string& key, const std::string& message) {
        // (built with append: GCC 12 warns falsely on chained operator+ here)
        std::string s;
        s.reserve(file.size() + key.size() + message.size() + 16);
        s.append(file);
        if (line > 0) s.append(":").append(std::to_string(line));
        if (!s.empty()) s.append(": ");
        if (!key.empty()) s.append(key).append(": ");
        s.append(message);
        return s;
    }
    std::string file_;
    int line_;
    std::string key_;
};

// 1e+09 -> "1e9", 0.25 -> "0.25": numbers in messages, without printf's exponent padding.
inline std::string shortNumber(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    std::string s = buf;
    const size_t e = s.find("e+");
    if (e != std::string::npos) {
        size_t digits = e + 2;
        while (digits + 1 < s.size() && s[digits] == '0') ++digits;
        s = s.substr(0, e + 1) + s.substr(digits);
    }
    return s;
}

[[noreturn]] inline void checkFailed(const char* cond, const char* file, int line) {
    std::fprintf(stderr, "internal error (bug): check failed: %s at %s:%d\n", cond, file, line);
    std::abort();
}

}  // namespace tpb

#define TPB_CHECK(cond)                                             \
    do {                                                            \
        if (!(cond)) ::tpb::checkFailed(#cond, __FILE__, __LINE__); \
    } while (0)
