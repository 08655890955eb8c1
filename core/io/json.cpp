// Strict JSON parser with line numbers. See json.h for what is accepted.
#include "io/json.h"

#include "base/error.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <unordered_map>

namespace tpb {

// ---- JsonValue helpers ---------------------------------------------------------------------------

const JsonMember* JsonValue::findMember(std::string_view key) const {
    for (const JsonMember& m : members)
        if (m.key == key) return &m;
    return nullptr;
}

const JsonValue* JsonValue::find(std::string_view key) const {
    const JsonMember* m = findMember(key);
    return m ? &m->value : nullptr;
}

const char* JsonValue::typeName() const {
    switch (type) {
        case Type::Null: return "null";
        case Type::Bool: return "a boolean";
        case Type::Number: return "a number";
        case Type::String: return "a string";
        case Type::Array: return "an array";
        case Type::Object: return "an object";
    }
    return "?";
}

namespace {

void appendBrief(const JsonValue& v, std::string& out, size_t maxChars) {
    if (out.size() > maxChars) return;
    switch (v.type) {
        case JsonValue::Type::Null: out += "null"; break;
        case JsonValue::Type::Bool: out += v.boolean ? "true" : "false"; break;
        case JsonValue::Type::Number: out += v.text; break;
        case JsonValue::Type::String: out += '"' + v.text + '"'; break;
        case JsonValue::Type::Array:
            out += '[';
            for (size_t i = 0; i < v.items.size() && out.size() <= maxChars; ++i) {
                if (i) out += ", ";
                appendBrief(v.items[i], out, maxChars);
            }
            out += ']';
            break;
        case JsonValue::Type::Object: out += v.members.empty() ? "{}" : "{...}"; break;
    }
}

}  // namespace

std::string JsonValue::brief(size_t maxChars) const {
    std::string out;
    appendBrief(*this, out, maxChars);
    if (out.size() > maxChars) out = out.substr(0, maxChars) + "...";
    return out;
}

bool isJsonCommentKey(std::string_view key) { return (!key.empty() && key[0] == '_') || key == "comment"; }

// ---- Parser --------------------------------------------------------------------------------------

namespace {

class Parser {
public:
    Parser(const std::string& text, const std::string& file) : s_(text), file_(file) {}

    JsonValue parseDocument() {
        if (s_.compare(0, 3, "\xEF\xBB\xBF") == 0) pos_ = 3;  // UTF-8 byte order mark
        if (const char* encoding = wideEncoding())
            fail(1, std::string("the file is ") + encoding +
                        " text, but scene files must be UTF-8; convert it (e.g. iconv -f " +
                        (std::string(encoding).rfind("UTF-32", 0) == 0 ? "UTF-32" : "UTF-16") +
                        " -t UTF-8 in.json > out.json) or save it as UTF-8 in the editor");
        skipWhitespace();
        if (atEnd()) fail(line_, "the file is empty: expected a JSON value");
        JsonValue v = parseValue(0);
        skipWhitespace();
        if (!atEnd()) fail(line_, "unexpected " + describeHere() + " after the end of the JSON value");
        return v;
    }

private:
    const std::string& s_;
    const std::string& file_;
    size_t pos_ = 0;
    int line_ = 1;

    // Editors on Windows often save "Unicode" text as UTF-16 (or, rarely, UTF-32), with or without
    // a byte order mark. JSON text here is UTF-8, and such a file would otherwise be reported as an
    // "unexpected byte 0xFF" or 0x00 that says nothing about the fix. A BOM, or a NUL in the first
    // two bytes (a scene starts with an ASCII character, "{" or whitespace), identifies them.
    const char* wideEncoding() const {
        const auto at = [&](size_t i) { return i < s_.size() ? static_cast<unsigned char>(s_[i]) : 0x100u; };
        if (at(0) == 0xFF && at(1) == 0xFE && at(2) == 0 && at(3) == 0) return "UTF-32 (little-endian)";
        if (at(0) == 0 && at(1) == 0 && at(2) == 0xFE && at(3) == 0xFF) return "UTF-32 (big-endian)";
        if (at(0) == 0xFF && at(1) == 0xFE) return "UTF-16 (little-endian)";
        if (at(0) == 0xFE && at(1) == 0xFF) return "UTF-16 (big-endian)";
        if (s_.size() >= 4 && at(0) != 0 && at(1) == 0 && at(2) == 0 && at(3) == 0) return "UTF-32 (little-endian)";
        if (s_.size() >= 4 && at(0) == 0 && at(1) == 0 && at(2) == 0 && at(3) != 0) return "UTF-32 (big-endian)";
        if (s_.size() >= 2 && at(0) != 0 && at(1) == 0) return "UTF-16 (little-endian)";
        if (s_.size() >= 2 && at(0) == 0 && at(1) != 0) return "UTF-16 (big-endian)";
        return nullptr;
    }

    [[noreturn]] void fail(int line, const std::string& message) const { throw UserError(file_, line, "", message); }

    bool atEnd() const { return pos_ >= s_.size(); }
    unsigned char peek() const { return atEnd() ? 0 : static_cast<unsigned char>(s_[pos_]); }

    void skipWhitespace() {
        while (!atEnd()) {
            const char c = s_[pos_];
            if (c == '\n')
                ++line_;
            else if (c != ' ' && c != '\t' && c != '\r')
                return;
            ++pos_;
        }
    }

    // "end of input", "'x'" or "byte 0x01" for the character at pos_.
    std::string describeHere() const {
        if (atEnd()) return "end of input";
        const unsigned char c = peek();
        if (c >= 0x20 && c < 0x7f) return std::string("'") + static_cast<char>(c) + "'";
        char buf[32];
        std::snprintf(buf, sizeof buf, "byte 0x%02X", c);
        return buf;
    }

    // ---- values ----

    JsonValue parseValue(int depth) {
        const unsigned char c = peek();
        switch (c) {
            case '{': return parseObject(depth + 1);
            case '[': return parseArray(depth + 1);
            case '"': {
                JsonValue v;
                v.type = JsonValue::Type::String;
                v.line = line_;
                v.text = parseString();
                return v;
            }
            case 't': return parseLiteral("true");
            case 'f': return parseLiteral("false");
            case 'n': return parseLiteral("null");
            default: break;
        }
        if (c == '-' || (c >= '0' && c <= '9')) return parseNumber();
        if (atEnd()) fail(line_, "unexpected end of input: expected a value");
        if (c == '/') fail(line_, "comments are not allowed in JSON (use a \"_comment\" key instead)");
        if (c == '\'') fail(line_, "strings must be in double quotes");
        if (c == '+') fail(line_, "a number must not start with '+'");
        if (c == '.') fail(line_, "a number must have a digit before '.'");
        if (c == '}' || c == ']' || c == ',' || c == ':')
            fail(line_, "unexpected " + describeHere() + ": expected a value");
        const std::string word = wordHere();
        if (isNanOrInf(word)) fail(line_, "NaN and Infinity are not valid JSON numbers");
        if (!word.empty()) fail(line_, "unexpected '" + word + "': expected a value (strings need double quotes)");
        fail(line_, "unexpected " + describeHere() + ": expected a value");
    }

    // The identifier-like run of characters at pos_ (for messages), at most 20 characters.
    std::string wordHere() const {
        std::string w;
        for (size_t i = pos_; i < s_.size() && w.size() < 20; ++i) {
            const char c = s_[i];
            const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
                            c == '-' || c == '+' || c == '.';
            if (!ok) break;
            w += c;
        }
        return w;
    }

    static bool isNanOrInf(std::string w) {
        if (!w.empty() && (w[0] == '-' || w[0] == '+')) w.erase(0, 1);
        for (char& ch : w) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
        return w == "nan" || w == "inf" || w == "infinity";
    }

    JsonValue parseLiteral(const char* word) {
        const std::string_view lit(word);
        if (s_.compare(pos_, lit.size(), lit) != 0 || isWordChar(pos_ + lit.size())) {
            const std::string w = wordHere();
            if (isNanOrInf(w)) fail(line_, "NaN and Infinity are not valid JSON numbers");
            fail(line_, "unexpected '" + w + "': expected a value (strings need double quotes)");
        }
        JsonValue v;
        v.line = line_;
        if (lit == "null") {
            v.type = JsonValue::Type::Null;
        } else {
            v.type = JsonValue::Type::Bool;
            v.boolean = lit == "true";
        }
        pos_ += lit.size();
        return v;
    }

    bool isWordChar(size_t i) const {
        if (i >= s_.size()) return false;
        const char c = s_[i];
        return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    }

    // ---- containers ----

    void checkDepth(int depth) const {
        if (depth > kJsonMaxDepth) fail(line_, "nesting deeper than " + std::to_string(kJsonMaxDepth) + " levels");
    }

    JsonValue parseObject(int depth) {
        checkDepth(depth);
        JsonValue obj;
        obj.type = JsonValue::Type::Object;
        obj.line = line_;
        ++pos_;                                     // '{'
        std::unordered_map<std::string, int> seen;  // key -> line, for duplicates
        skipWhitespace();
        if (peek() == '}') {
            ++pos_;
            return obj;
        }
        for (;;) {
            skipWhitespace();
            if (atEnd()) unclosed("object", obj.line);
            if (peek() != '"') {
                if (peek() == '}' && !obj.members.empty()) fail(line_, "trailing comma before '}' is not allowed");
                if (peek() == '\'') fail(line_, "object keys must be in double quotes");
                fail(line_, "unexpected " + describeHere() + ": expected a key in double quotes");
            }
            JsonMember m;
            m.line = line_;
            m.key = parseString();
            if (!isJsonCommentKey(m.key)) {
                auto [it, inserted] = seen.emplace(m.key, m.line);
                if (!inserted)
                    fail(m.line,
                         "duplicate key \"" + m.key + "\" (first written at line " + std::to_string(it->second) + ")");
            }
            skipWhitespace();
            if (atEnd()) unclosed("object", obj.line);
            if (peek() != ':')
                fail(line_, "unexpected " + describeHere() + ": expected ':' after key \"" + m.key + "\"");
            ++pos_;
            skipWhitespace();
            if (atEnd()) unclosed("object", obj.line);
            m.value = parseValue(depth);
            obj.members.push_back(std::move(m));
            skipWhitespace();
            if (atEnd()) unclosed("object", obj.line);
            const unsigned char c = peek();
            ++pos_;
            if (c == '}') return obj;
            if (c != ',') {
                --pos_;
                fail(line_, "unexpected " + describeHere() + ": expected ',' or '}' after the value of \"" +
                                obj.members.back().key + "\"");
            }
        }
    }

    JsonValue parseArray(int depth) {
        checkDepth(depth);
        JsonValue arr;
        arr.type = JsonValue::Type::Array;
        arr.line = line_;
        ++pos_;  // '['
        skipWhitespace();
        if (peek() == ']') {
            ++pos_;
            return arr;
        }
        for (;;) {
            skipWhitespace();
            if (atEnd()) unclosed("array", arr.line);
            if (peek() == ']') fail(line_, "trailing comma before ']' is not allowed");
            arr.items.push_back(parseValue(depth));
            skipWhitespace();
            if (atEnd()) unclosed("array", arr.line);
            const unsigned char c = peek();
            ++pos_;
            if (c == ']') return arr;
            if (c != ',') {
                --pos_;
                fail(line_, "unexpected " + describeHere() + ": expected ',' or ']' in the array");
            }
        }
    }

    [[noreturn]] void unclosed(const char* what, int openLine) const {
        fail(line_, std::string("unexpected end of input: the ") + what + " opened at line " +
                        std::to_string(openLine) + " is not closed");
    }

    // ---- numbers ----

    static bool isDigit(unsigned char c) { return c >= '0' && c <= '9'; }

    JsonValue parseNumber() {
        JsonValue v;
        v.type = JsonValue::Type::Number;
        v.line = line_;
        const size_t start = pos_;
        if (peek() == '-') {
            ++pos_;
            if (peek() == 'I' || peek() == 'i' || peek() == 'N' || peek() == 'n')
                fail(line_, "NaN and Infinity are not valid JSON numbers");
            if (!isDigit(peek())) fail(line_, "expected a digit after '-'");
        }
        if (peek() == '0') {
            ++pos_;
            if (isDigit(peek())) fail(line_, "numbers must not have leading zeros");
        } else {
            while (isDigit(peek())) ++pos_;
        }
        if (peek() == '.') {
            ++pos_;
            if (!isDigit(peek())) fail(line_, "expected a digit after '.' in a number");
            while (isDigit(peek())) ++pos_;
        }
        if (peek() == 'e' || peek() == 'E') {
            ++pos_;
            if (peek() == '+' || peek() == '-') ++pos_;
            if (!isDigit(peek())) fail(line_, "expected a digit in the exponent of a number");
            while (isDigit(peek())) ++pos_;
        }
        if (isWordChar(pos_) || peek() == '.')
            fail(line_, "invalid number '" + s_.substr(start, pos_ - start + 1) + "...'");
        v.text = s_.substr(start, pos_ - start);
        v.number = toDouble(v.text);
        return v;
    }

    // `lit` is a valid JSON number literal.
    double toDouble(const std::string& lit) const {
        double d = 0.0;
        const char* first = lit.data();
        const char* last = lit.data() + lit.size();
        const auto [ptr, ec] = std::from_chars(first, last, d, std::chars_format::general);
        if (ec == std::errc() && ptr == last && std::isfinite(d)) return d;
        // Out of range: either too large (error) or too small (rounds to zero).
        if (decimalExponent(lit) > 0)
            fail(line_, "number " + (lit.size() > 40 ? lit.substr(0, 40) + "..." : lit) +
                            " is out of the range of a double (about 1.8e308)");
        return lit[0] == '-' ? -0.0 : 0.0;
    }

    // Decimal exponent of the leading significant digit of a literal (saturating), for example
    // 2 for "123.4", -3 for "0.00123", 10 for "1e10". Literal without non-zero digits: 0.
    static long long decimalExponent(const std::string& lit) {
        size_t i = lit[0] == '-' ? 1 : 0;
        long long intDigits = 0, leadPos = 0;
        bool found = false;
        for (; i < lit.size() && isDigit(lit[i]); ++i) {
            if (!found && lit[i] != '0') {
                found = true;
                leadPos = intDigits;
            }
            ++intDigits;
        }
        long long lead = 0;
        if (found) {
            lead = intDigits - 1 - leadPos;
        }
        if (i < lit.size() && lit[i] == '.') {
            ++i;
            long long fracPos = 0;
            for (; i < lit.size() && isDigit(lit[i]); ++i, ++fracPos) {
                if (!found && lit[i] != '0') {
                    found = true;
                    lead = -(fracPos + 1);
                }
            }
        }
        if (!found) return 0;
        long long exp = 0;
        if (i < lit.size() && (lit[i] == 'e' || lit[i] == 'E')) {
            ++i;
            bool neg = false;
            if (lit[i] == '+' || lit[i] == '-') neg = lit[i++] == '-';
            for (; i < lit.size(); ++i) {
                if (exp < 1000000000LL) exp = exp * 10 + (lit[i] - '0');
            }
            if (neg) exp = -exp;
        }
        return lead + exp;
    }

    // ---- strings ----

    static int hexValue(unsigned char c) {
        if (c >= '0' && c <= '9') return c - '0';
        if (c >= 'a' && c <= 'f') return c - 'a' + 10;
        if (c >= 'A' && c <= 'F') return c - 'A' + 10;
        return -1;
    }

    // Reads the 4 hex digits after "\u" (pos_ is on the first digit).
    unsigned readHex4() {
        unsigned v = 0;
        for (int k = 0; k < 4; ++k) {
            const int h = hexValue(peek());
            if (atEnd() || h < 0) fail(line_, "invalid \\u escape: expected 4 hexadecimal digits");
            v = v * 16 + static_cast<unsigned>(h);
            ++pos_;
        }
        return v;
    }

    static void appendUtf8(std::string& out, unsigned cp) {
        if (cp < 0x80) {
            out += static_cast<char>(cp);
        } else if (cp < 0x800) {
            out += static_cast<char>(0xC0 | (cp >> 6));
            out += static_cast<char>(0x80 | (cp & 0x3F));
        } else if (cp < 0x10000) {
            out += static_cast<char>(0xE0 | (cp >> 12));
            out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
            out += static_cast<char>(0x80 | (cp & 0x3F));
        } else {
            out += static_cast<char>(0xF0 | (cp >> 18));
            out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
            out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
            out += static_cast<char>(0x80 | (cp & 0x3F));
        }
    }

    // Length of the valid UTF-8 sequence starting at byte `i` (lead byte >= 0x80), or 0.
    size_t utf8SequenceLength(size_t i) const {
        const auto byte = [&](size_t k) -> unsigned { return k < s_.size() ? static_cast<unsigned char>(s_[k]) : 0u; };
        const unsigned b0 = byte(i);
        size_t n = 0;
        unsigned lo = 0x80, hi = 0xBF;  // allowed range of the second byte
        if (b0 >= 0xC2 && b0 <= 0xDF)
            n = 2;
        else if (b0 == 0xE0) {
            n = 3;
            lo = 0xA0;
        } else if (b0 == 0xED) {
            n = 3;
            hi = 0x9F;
        }  // no UTF-16 surrogates
        else if (b0 >= 0xE1 && b0 <= 0xEF)
            n = 3;
        else if (b0 == 0xF0) {
            n = 4;
            lo = 0x90;
        } else if (b0 >= 0xF1 && b0 <= 0xF3)
            n = 4;
        else if (b0 == 0xF4) {
            n = 4;
            hi = 0x8F;
        }  // <= U+10FFFF
        else
            return 0;
        const unsigned b1 = byte(i + 1);
        if (b1 < lo || b1 > hi) return 0;
        for (size_t k = 2; k < n; ++k) {
            const unsigned b = byte(i + k);
            if (b < 0x80 || b > 0xBF) return 0;
        }
        return n;
    }

    // pos_ is on the opening quote; returns the decoded contents and leaves pos_ after the closing one.
    std::string parseString() {
        const int startLine = line_;
        ++pos_;
        std::string out;
        for (;;) {
            if (atEnd())
                fail(line_, "unexpected end of input: the string opened at line " + std::to_string(startLine) +
                                " is not closed");
            const unsigned char c = peek();
            if (c == '"') {
                ++pos_;
                return out;
            }
            if (c == '\n') fail(line_, "the string opened here is not closed on its line");
            if (c < 0x20) {
                char buf[96];
                std::snprintf(buf, sizeof buf,
                              "control character U+%04X in a string: write it as an escape (\\t, \\u00XX)", c);
                fail(line_, buf);
            }
            if (c == '\\') {
                ++pos_;
                parseEscape(out);
                continue;
            }
            if (c < 0x80) {
                out += static_cast<char>(c);
                ++pos_;
                continue;
            }
            const size_t n = utf8SequenceLength(pos_);
            if (n == 0) fail(line_, "invalid UTF-8 in a string (the file must be UTF-8)");
            out.append(s_, pos_, n);
            pos_ += n;
        }
    }

    // pos_ is after the backslash.
    void parseEscape(std::string& out) {
        if (atEnd()) fail(line_, "unexpected end of input in a string escape");
        const unsigned char e = peek();
        ++pos_;
        switch (e) {
            case '"': out += '"'; return;
            case '\\': out += '\\'; return;
            case '/': out += '/'; return;
            case 'b': out += '\b'; return;
            case 'f': out += '\f'; return;
            case 'n': out += '\n'; return;
            case 'r': out += '\r'; return;
            case 't': out += '\t'; return;
            case 'u': break;
            default: {
                --pos_;
                fail(line_, "invalid escape \\" + describeHere() +
                                " in a string; allowed: \\\" \\\\ \\/ \\b \\f \\n \\r \\t \\uXXXX");
            }
        }
        unsigned cp = readHex4();
        if (cp >= 0xDC00 && cp <= 0xDFFF) fail(line_, "invalid \\u escape: unpaired low surrogate \\u" + hex4(cp));
        if (cp >= 0xD800 && cp <= 0xDBFF) {
            if (s_.compare(pos_, 2, "\\u") != 0)
                fail(line_, "invalid \\u escape: high surrogate \\u" + hex4(cp) +
                                " must be followed by a low surrogate \\uDC00-\\uDFFF");
            pos_ += 2;
            const unsigned lo = readHex4();
            if (lo < 0xDC00 || lo > 0xDFFF)
                fail(line_, "invalid \\u escape: high surrogate \\u" + hex4(cp) +
                                " must be followed by a low surrogate \\uDC00-\\uDFFF");
            cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
        }
        appendUtf8(out, cp);
    }

    static std::string hex4(unsigned v) {
        char buf[8];
        std::snprintf(buf, sizeof buf, "%04X", v & 0xFFFFu);
        return buf;
    }
};

}  // namespace

JsonValue parseJson(const std::string& text, const std::string& file) { return Parser(text, file).parseDocument(); }

}  // namespace tpb
