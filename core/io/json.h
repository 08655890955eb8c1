// A small strict JSON (RFC 8259) parser whose value tree remembers the line of every value and of
// every object key, so that the scene loader can report "scene.json:14: lights[0].power: ...".
//
// Strict: no comments, no trailing commas, no NaN/Infinity, no single quotes, no leading zeros,
// numbers must fit a double, strings must be valid UTF-8 (raw or \u escapes with paired
// surrogates), duplicate keys are errors, nesting is limited to kJsonMaxDepth. Every error throws
// tpb::UserError(file, line, "", message). One convenience for hand-written files: keys that start
// with "_" or are exactly "comment" are comment keys (see isJsonCommentKey); the parser keeps them
// and lets them repeat, and the loader ignores them.
//
// The parser never recurses deeper than kJsonMaxDepth, never reads past the input and does work
// linear in its size (plus a hash lookup per key), so it is safe on hostile input (fuzzed).
#pragma once
#include <string>
#include <string_view>
#include <vector>

namespace tpb {

inline constexpr int kJsonMaxDepth = 256;

struct JsonMember;

struct JsonValue {
    enum class Type { Null, Bool, Number, String, Array, Object };

    Type type = Type::Null;
    int line = 0;                     // 1-based line where the value starts
    bool boolean = false;             // Bool
    double number = 0.0;              // Number
    std::string text;                 // String: decoded UTF-8; Number: the literal as written (exact integers)
    std::vector<JsonValue> items;     // Array
    std::vector<JsonMember> members;  // Object, in file order

    bool isNull() const { return type == Type::Null; }
    bool isBool() const { return type == Type::Bool; }
    bool isNumber() const { return type == Type::Number; }
    bool isString() const { return type == Type::String; }
    bool isArray() const { return type == Type::Array; }
    bool isObject() const { return type == Type::Object; }

    // First member named `key`, or nullptr (also when this is not an object).
    const JsonMember* findMember(std::string_view key) const;
    const JsonValue* find(std::string_view key) const;

    // "a number", "an array", ... for messages.
    const char* typeName() const;
    // Short JSON-like rendering for messages (numbers as written), cut to about `maxChars`.
    std::string brief(size_t maxChars = 60) const;
};

struct JsonMember {
    std::string key;
    int line = 0;  // line of the key
    JsonValue value;
};

// Keys the loader treats as comments: "_anything" and "comment".
bool isJsonCommentKey(std::string_view key);

// Parses a whole document (one value, surrounded by optional whitespace; a leading UTF-8 BOM is
// skipped). `file` is only used in error messages.
JsonValue parseJson(const std::string& text, const std::string& file);

}  // namespace tpb
