// Numbers as the user typed them (parse_number.h).
#include "cullide/parse_number.h"

#include "cullide/error.h"

#include <charconv>
#include <cmath>
#include <limits>

namespace cullide {

namespace {

// The text as a message quotes it: hostile input can be megabytes long.
std::string shown(std::string_view text) {
    constexpr size_t kShown = 40;
    return text.size() <= kShown ? std::string(text) : std::string(text.substr(0, kShown)) + "...";
}

[[noreturn]] void notA(std::string_view text, const std::string& name, const char* what) {
    throw InputError(name, "'" + shown(text) + "' is not " + what);
}

template <typename T>
[[noreturn]] void outOfRange(std::string_view text, const std::string& name, T min, T max) {
    throw InputError(name, shown(text) + " is out of range (" + numberText(min) + " to " + numberText(max) + ")");
}

// The sign and the magnitude of an integer text; `negative` for a leading '-'. Throws "not an
// integer" for anything but an optional sign and decimal digits; a magnitude beyond 64 bits is
// out of range.
unsigned long long magnitude(std::string_view text, const std::string& name, bool& negative,
                             unsigned long long limit, auto&& outside) {
    std::string_view digits = text;
    negative = !digits.empty() && digits.front() == '-';
    if (!digits.empty() && (digits.front() == '-' || digits.front() == '+')) digits.remove_prefix(1);
    if (digits.empty() || digits.front() < '0' || digits.front() > '9') notA(text, name, "an integer");
    unsigned long long v = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
    if (end != digits.data() + digits.size()) notA(text, name, "an integer");
    if (ec == std::errc::result_out_of_range || v > limit) outside();
    return v;
}

}  // namespace

std::string realText(double v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

long long parseSigned(std::string_view text, const std::string& name, long long min, long long max) {
    bool negative = false;
    auto outside = [&] { outOfRange(text, name, min, max); };
    const unsigned long long limit = 1ull << 63;  // |LLONG_MIN|; above LLONG_MAX only when negative
    const unsigned long long m = magnitude(text, name, negative, limit, outside);
    if (!negative && m == limit) outside();
    const long long v = negative ? (m == limit ? std::numeric_limits<long long>::min() : -(long long)m) : (long long)m;
    if (v < min || v > max) outside();
    return v;
}

unsigned long long parseUnsigned(std::string_view text, const std::string& name, unsigned long long min,
                                 unsigned long long max) {
    bool negative = false;
    auto outside = [&] { outOfRange(text, name, min, max); };
    const unsigned long long v = magnitude(text, name, negative, std::numeric_limits<unsigned long long>::max(), outside);
    if ((negative && v != 0) || v < min || v > max) outside();
    return v;
}

double parseReal(std::string_view text, const std::string& name, double min, double max) {
    std::string_view number = text;
    const bool plus = !number.empty() && number.front() == '+';
    if (plus) number.remove_prefix(1);
    if (number.empty() || (plus && number.front() == '-')) notA(text, name, "a number");
    double v = 0;
    const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), v);
    if (ec == std::errc::invalid_argument || end != number.data() + number.size()) notA(text, name, "a number");
    if (ec == std::errc::result_out_of_range) outOfRange(text, name, min, max);
    if (std::isnan(v) || (std::isinf(v) && !std::isinf(v < 0 ? min : max))) notA(text, name, "a finite number");
    if (!(v >= min && v <= max)) outOfRange(text, name, min, max);
    return v;
}

}  // namespace cullide
