// Numbers as the user typed them: the one strict reading behind every number an option, a list
// item, a part of a value (the W of WxH, the K of auto:K), a study scene or a Python argument
// gives (options.h, the `cullide` commands, the study, the Python module).
//
//   - The whole text is the number: decimal digits after an optional sign ('-' or '+'); a real
//     number may have a fraction and an exponent (2.5, .5, 1e-3). No spaces, no hexadecimal, no
//     characters after the number.
//   - The number is read exactly, then checked against [min, max]: a value beyond its type's
//     limits is out of range like any other, never wrapped or clamped (-1 for a count,
//     4294967396 for a viewport side, 2^64 for a seed).
//   - NaN is never a number; an infinity only where the range includes it (min -inf or max +inf).
//
// Errors are InputError(name, cause), the cause quoting the text as typed (cut short if long):
//   "'12x' is not an integer", "'nan' is not a finite number",
//   "4294967396 is out of range (1 to 16384)".
#pragma once

#include "cullide/error.h"

#include <string>
#include <string_view>
#include <type_traits>

namespace cullide {

long long parseSigned(std::string_view text, const std::string& name, long long min, long long max);
unsigned long long parseUnsigned(std::string_view text, const std::string& name, unsigned long long min,
                                 unsigned long long max);
double parseReal(std::string_view text, const std::string& name, double min, double max);

// parseSigned, parseUnsigned or parseReal by T, with T's bounds.
template <typename T>
T parseNumber(std::string_view text, const std::string& name, T min, T max) {
    static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>);
    if constexpr (std::is_floating_point_v<T>) return T(parseReal(text, name, double(min), double(max)));
    else if constexpr (std::is_signed_v<T>) return T(parseSigned(text, name, min, max));
    else return T(parseUnsigned(text, name, min, max));
}

// A real number in the shortest form that reads back the same (0.5, 1e+06).
std::string realText(double v);
// A bound or value as the messages write it: integers in full, reals as realText.
template <typename T>
std::string numberText(T v) {
    if constexpr (std::is_floating_point_v<T>) return realText(double(v));
    else return std::to_string(v);
}

// A value that arrived as a number (a field of OptionText, a Python int) checked against
// [min, max] in the words of parseNumber: "0 is out of range (1 to 1000000)".
template <typename T>
T checkRange(T v, const std::string& name, T min, T max) {
    if (!(v >= min && v <= max))
        throw InputError(name, numberText(v) + " is out of range (" + numberText(min) + " to " + numberText(max) + ")");
    return v;
}

}  // namespace cullide
