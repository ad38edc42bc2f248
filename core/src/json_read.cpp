// The JSON reader of every JSON input (see json_read.h): nlohmann's SAX parser, driven over the
// text by an iterator that counts the bytes read (so that errors found by the builder have a
// position too), and a builder that makes the value with the limits checked as it goes.
#include "cullide/json_read.h"

#include "cullide/error.h"
#include "cullide/file_io.h"

#include <iterator>
#include <memory>
#include <new>
#include <type_traits>
#include <unordered_set>
#include <utility>
#include <vector>

namespace cullide {
namespace {

// Walks the text for the parser, leaving the count of bytes read where the builder can see it.
class CountingIterator {
public:
    using iterator_category = std::input_iterator_tag;
    using value_type = char;
    using difference_type = std::ptrdiff_t;
    using pointer = const char*;
    using reference = const char&;

    CountingIterator(const char* p, const char** read) : p_(p), read_(read) {}
    reference operator*() const { return *p_; }
    CountingIterator& operator++() {
        *read_ = ++p_;
        return *this;
    }
    CountingIterator operator++(int) {
        CountingIterator old = *this;
        ++*this;
        return old;
    }
    bool operator==(const CountingIterator& o) const { return p_ == o.p_; }
    bool operator!=(const CountingIterator& o) const { return p_ != o.p_; }

private:
    const char* p_;
    const char** read_;
};

// Builds the value from the parser's events; stops the parse (returns false) at the first
// problem, which it keeps as `error`.
template <class J>
class Builder {
public:
    using Object = typename J::object_t;
    static constexpr bool kOrdered = !std::is_same_v<Object, typename nlohmann::json::object_t>;

    Builder(size_t maxDepth, const char* start, const char* const* read)
        : maxDepth_(maxDepth), start_(start), read_(read) {}

    J root;
    std::string error;  // the cause, without the position
    size_t errorAt = 0;  // bytes read when the builder found it (0: the parser's error)
    size_t parserAt = 0;
    std::string parserError;

    bool null() { return put(nullptr) != nullptr; }
    bool boolean(bool b) { return put(b) != nullptr; }
    bool number_integer(typename J::number_integer_t n) { return put(n) != nullptr; }
    bool number_unsigned(typename J::number_unsigned_t n) { return put(n) != nullptr; }
    bool number_float(typename J::number_float_t x, const typename J::string_t&) { return put(x) != nullptr; }
    bool string(typename J::string_t& s) { return put(std::move(s)) != nullptr; }
    bool binary(typename J::binary_t& b) { return put(std::move(b)) != nullptr; }

    bool start_object(size_t) { return open(J::value_t::object); }
    bool start_array(size_t) { return open(J::value_t::array); }
    bool end_object() { return close(); }
    bool end_array() { return close(); }

    bool key(typename J::string_t& k) {
        Open& o = stack_.back();
        Object& obj = *o.value->template get_ptr<Object*>();
        if constexpr (kOrdered) {
            // ordered_map looks keys up one by one: a set beside a large object keeps a document
            // of many keys linear.
            bool fresh = true;
            if (obj.size() < kScanKeys) {
                for (const auto& kv : obj) fresh &= kv.first != k;
            } else {
                if (!o.keys) {
                    o.keys = std::make_unique<std::unordered_set<std::string>>();
                    for (const auto& kv : obj) o.keys->insert(kv.first);
                }
                fresh = o.keys->insert(k).second;
            }
            if (!fresh) return fail("duplicate key '" + shown(k) + "'");
            // The key is new: appended as it is, without ordered_map's own search.
            auto& entries = static_cast<typename Object::Container&>(obj);
            entries.emplace_back(std::move(k), nullptr);
            slot_ = &entries.back().second;
        } else {
            const auto [it, fresh] = obj.try_emplace(std::move(k));
            if (!fresh) return fail("duplicate key '" + shown(it->first) + "'");
            slot_ = &it->second;
        }
        return true;
    }

    bool parse_error(size_t position, const std::string&, const nlohmann::detail::exception& e) {
        parserAt = position;
        parserError = e.what();
        return false;
    }

private:
    static constexpr size_t kScanKeys = 16;

    // A key as a message shows it: escaped as in JSON (a NUL or a newline in a key must not cut or
    // break the message), and at most 80 characters of it.
    static std::string shown(const std::string& key) {
        std::string s =
            nlohmann::json(key.substr(0, 80)).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
        s = s.substr(1, s.size() - 2);
        return key.size() > 80 ? s + "..." : s;
    }

    struct Open {
        J* value;
        std::unique_ptr<std::unordered_set<std::string>> keys;  // an ordered object's, once large
    };

    bool fail(std::string cause) {
        error = std::move(cause);
        errorAt = size_t(*read_ - start_);
        return false;
    }

    // The new value's place: the root, the next element of the open array, or the slot of the
    // key just read. Pointers to open containers stay valid: only the innermost one grows.
    template <class V>
    J* put(V&& v) {
        if (stack_.empty()) {
            root = J(std::forward<V>(v));
            return &root;
        }
        J& top = *stack_.back().value;
        if (top.is_array()) {
            auto& a = *top.template get_ptr<typename J::array_t*>();
            a.emplace_back(std::forward<V>(v));
            return &a.back();
        }
        *slot_ = J(std::forward<V>(v));
        return slot_;
    }

    bool open(typename J::value_t type) {
        if (stack_.size() >= maxDepth_) return fail("JSON nested deeper than " + std::to_string(maxDepth_) + " levels");
        stack_.push_back({put(type), nullptr});
        return true;
    }

    bool close() {
        stack_.pop_back();
        return true;
    }

    size_t maxDepth_;
    const char* start_;
    const char* const* read_;
    std::vector<Open> stack_;
    J* slot_ = nullptr;
};

// "line L, column C" of the byte at 0-based offset `at`.
std::string lineAndColumn(std::string_view text, size_t at) {
    at = std::min(at, text.size());
    size_t line = 1, lineStart = 0;
    for (size_t i = 0; i < at; ++i)
        if (text[i] == '\n') ++line, lineStart = i + 1;
    return "line " + std::to_string(line) + ", column " + std::to_string(at - lineStart + 1);
}

template <class J>
J parse(std::string_view text, const std::string& source, const JsonLimits& limits) {
    checkJsonSize(text.size(), source, limits);
    const std::string part = limits.part ? std::string(limits.part) + ": " : "";
    const char* read = text.data();
    Builder<J> b(limits.maxDepth, text.data(), &read);
    try {
        const char* end = text.data() + text.size();
        if (J::sax_parse(CountingIterator(text.data(), &read), CountingIterator(end, &read), &b,
                         nlohmann::json::input_format_t::json, /*strict=*/true, /*ignore_comments=*/false))
            return std::move(b.root);
    } catch (const std::bad_alloc&) {
        throw InputError(source, part + "out of memory parsing " + std::to_string(text.size()) + " bytes of JSON");
    }
    if (!b.error.empty()) {
        // errorAt counts the bytes read up to the end of the token at fault: its last byte.
        const size_t at = b.errorAt == 0 ? 0 : b.errorAt - 1;
        throw InputError(source,
                         part + b.error + " at byte " + std::to_string(at + 1) + " (" + lineAndColumn(text, at) + ")");
    }
    // nlohmann's own message: "[json.exception.parse_error.101] parse error at line 1, column 5:
    // syntax error ..." or "[json.exception.out_of_range.406] number overflow parsing '1e999'";
    // the position is said once, in the same words as above.
    std::string what = b.parserError;
    const size_t bracket = what.find("] ");
    if (bracket != std::string::npos) what = what.substr(bracket + 2);
    const size_t colon = what.find(": ");
    if (what.rfind("parse error", 0) == 0 && colon != std::string::npos) what = what.substr(colon + 2);
    const size_t at = b.parserAt == 0 ? 0 : b.parserAt - 1;
    throw InputError(source, part + "malformed JSON at " + lineAndColumn(text, at) + ": " + what);
}

}  // namespace

void checkJsonSize(uint64_t bytes, const std::string& source, const JsonLimits& limits) {
    if (bytes <= limits.maxBytes) return;
    const uint64_t mib = limits.maxBytes >> 20;
    throw InputError(source,
                     (limits.part ? std::string(limits.part) + ": " : std::string()) + std::to_string(bytes) +
                         " bytes of JSON, over the limit of " + std::to_string(limits.maxBytes) + " bytes" +
                         (mib << 20 == limits.maxBytes ? " (" + std::to_string(mib) + " MiB)" : "") + " for " +
                         limits.kind);
}

nlohmann::json parseJson(std::string_view text, const std::string& source, const JsonLimits& limits) {
    return parse<nlohmann::json>(text, source, limits);
}

nlohmann::ordered_json parseOrderedJson(std::string_view text, const std::string& source, const JsonLimits& limits) {
    return parse<nlohmann::ordered_json>(text, source, limits);
}

nlohmann::json readJsonFile(const std::filesystem::path& path, const JsonLimits& limits) {
    const std::string text = readFile(path, limits.maxBytes, limits.kind);
    return parseJson(text, path.string(), limits);
}

}  // namespace cullide
