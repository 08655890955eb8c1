// Words in messages: a "did you mean" for a mistyped name (scene keys, flags) and a long echoed
// input clipped to a readable length.
#pragma once
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdlib>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace tpb {

// Edit distance counting insertions, deletions, substitutions and swaps of neighbours (optimal
// string alignment), case-insensitive.
inline size_t editDistance(std::string_view a, std::string_view b) {
    const auto low = [](char c) { return std::tolower(static_cast<unsigned char>(c)); };
    const size_t n = a.size(), m = b.size();
    std::vector<size_t> d((n + 1) * (m + 1));
    const auto at = [&](size_t i, size_t j) -> size_t& { return d[i * (m + 1) + j]; };
    for (size_t i = 0; i <= n; ++i) at(i, 0) = i;
    for (size_t j = 0; j <= m; ++j) at(0, j) = j;
    for (size_t i = 1; i <= n; ++i) {
        for (size_t j = 1; j <= m; ++j) {
            const size_t cost = low(a[i - 1]) == low(b[j - 1]) ? 0 : 1;
            at(i, j) = std::min({at(i - 1, j) + 1, at(i, j - 1) + 1, at(i - 1, j - 1) + cost});
            if (i > 1 && j > 1 && low(a[i - 1]) == low(b[j - 2]) && low(a[i - 2]) == low(b[j - 1]))
                at(i, j) = std::min(at(i, j), at(i - 2, j - 2) + 1);
        }
    }
    return at(n, m);
}

// The candidate closest to `word` when it is close (at most 2 edits, and fewer than half the
// longer name's letters), else "". Words longer than 64 characters are not compared.
inline std::string closestName(std::string_view word, const std::vector<std::string>& candidates) {
    if (word.size() > 64) return "";
    const std::string* best = nullptr;
    size_t bestD = SIZE_MAX;
    for (const std::string& c : candidates) {
        const size_t d = editDistance(word, c);
        if (d < bestD) {
            bestD = d;
            best = &c;
        }
    }
    const size_t longest = best ? std::max(word.size(), best->size()) : 0;
    if (!best || bestD > 2 || 2 * bestD >= longest) return "";
    return *best;
}

// " (did you mean \"x\"?)" when a candidate is close to `word` (closestName), else "".
inline std::string suggestion(std::string_view word, const std::vector<std::string>& candidates) {
    const std::string best = closestName(word, candidates);
    return best.empty() ? "" : " (did you mean \"" + best + "\"?)";
}

// `s` as it may be echoed in a message: whole up to `keep` characters, else its first `keep`
// characters, "..." and its length ("aaaa... (1048576 characters)"), so that a megabyte of input
// does not become a megabyte of error message.
inline std::string clipped(std::string_view s, size_t keep = 60) {
    if (s.size() <= keep + 20) return std::string(s);
    return std::string(s.substr(0, keep)) + "... (" + std::to_string(s.size()) + " characters)";
}

// The shortest decimal that reads back as `v` exactly ("0.3", not "0.29999999999999999").
inline std::string shortest(double v) {
    char b[32];
    const auto r = std::to_chars(b, b + sizeof b, v);
    return std::string(b, r.ptr);
}

// `s` with every number written as %.17g (a fingerprint's values: "(0.29999999999999999, 1, 2)")
// rewritten by shortest(), for people; words with digits in them ("beam2d", a hash) are kept.
inline std::string withShortestNumbers(const std::string& s) {
    const auto word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.'; };
    const auto numeric = [](char c) {
        return std::isdigit(static_cast<unsigned char>(c)) || c == '.' || c == 'e' || c == 'E' || c == '+' || c == '-';
    };
    std::string out;
    size_t i = 0;
    while (i < s.size()) {
        const bool starts =
            (std::isdigit(static_cast<unsigned char>(s[i])) || s[i] == '-') && (i == 0 || !word(s[i - 1]));
        size_t j = i;
        if (starts)
            while (j < s.size() && numeric(s[j])) ++j;
        if (starts && (j == s.size() || !word(s[j]))) {
            const std::string token = s.substr(i, j - i);
            char* end = nullptr;
            const double v = std::strtod(token.c_str(), &end);
            out += end == token.c_str() + token.size() ? shortest(v) : token;
            i = j;
        } else {
            out.push_back(s[i++]);
        }
    }
    return out;
}

}  // namespace tpb
