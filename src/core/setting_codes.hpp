// SPDX-License-Identifier: MIT
// The numbers of the enumerated settings, one table each: a value's code is its position in its table. They are
// kissm.h's KISSM_NONFINITE_*, KISSM_VIEWPOINT_*, KISSM_REFINE_* and KISSM_SUPPRESS_* (src/capi/config.cpp checks
// every entry at compile time) and the bytes of the features format (docs/features-format.md). A new value goes at
// the end of its table, so no stored code changes meaning.
#pragma once

#include <cstddef>
#include <cstdint>

#include "detail_namespace.hpp"
#include "params.hpp"

KISSM_DETAIL_BEGIN

template <class E>
struct SettingCodes;

template <>
struct SettingCodes<NonFinitePolicy> {
    static constexpr NonFinitePolicy values[] = {NonFinitePolicy::Reject, NonFinitePolicy::Drop};
};
template <>
struct SettingCodes<ViewpointMode> {
    static constexpr ViewpointMode values[] = {ViewpointMode::Fixed, ViewpointMode::CloudCenter,
                                               ViewpointMode::SignFree, ViewpointMode::Local};
};
template <>
struct SettingCodes<RefineMode> {
    static constexpr RefineMode values[] = {RefineMode::None, RefineMode::Gicp, RefineMode::PointToPlane};
};
template <>
struct SettingCodes<Suppression> {
    static constexpr Suppression values[] = {Suppression::None, Suppression::Ground};
};

// The largest code of E's table.
template <class E>
constexpr std::int32_t max_setting_code() {
    return static_cast<std::int32_t>(sizeof(SettingCodes<E>::values) / sizeof(SettingCodes<E>::values[0])) - 1;
}

// The code of v (its position in E's table).
template <class E>
constexpr std::int32_t setting_code(E v) {
    for (std::int32_t i = 0; i <= max_setting_code<E>(); ++i)
        if (SettingCodes<E>::values[i] == v) return i;
    return -1; // not reached: every value is in its table (tests/core/test_setting_codes.cpp)
}

// The value of code (in [0, max_setting_code<E>()], which the caller has checked); the table's first otherwise.
template <class E>
constexpr E setting_of(std::int32_t code) {
    return code >= 0 && code <= max_setting_code<E>() ? SettingCodes<E>::values[code] : SettingCodes<E>::values[0];
}

// Every enumerator, counted by a switch without default: -Wswitch (an error in every build) stops a new enumerator
// that is not counted here, and the static_asserts one that is counted but missing from its table.
constexpr std::int32_t enumerators(NonFinitePolicy v) {
    switch (v) {
    case NonFinitePolicy::Reject:
    case NonFinitePolicy::Drop: return 2;
    }
    return 0;
}
constexpr std::int32_t enumerators(ViewpointMode v) {
    switch (v) {
    case ViewpointMode::Fixed:
    case ViewpointMode::CloudCenter:
    case ViewpointMode::SignFree:
    case ViewpointMode::Local: return 4;
    }
    return 0;
}
constexpr std::int32_t enumerators(RefineMode v) {
    switch (v) {
    case RefineMode::None:
    case RefineMode::Gicp:
    case RefineMode::PointToPlane: return 3;
    }
    return 0;
}
constexpr std::int32_t enumerators(Suppression v) {
    switch (v) {
    case Suppression::None:
    case Suppression::Ground: return 2;
    }
    return 0;
}
static_assert(enumerators(NonFinitePolicy::Reject) == max_setting_code<NonFinitePolicy>() + 1, "NonFinitePolicy table");
static_assert(enumerators(ViewpointMode::Fixed) == max_setting_code<ViewpointMode>() + 1, "ViewpointMode table");
static_assert(enumerators(RefineMode::None) == max_setting_code<RefineMode>() + 1, "RefineMode table");
static_assert(enumerators(Suppression::None) == max_setting_code<Suppression>() + 1, "Suppression table");

KISSM_DETAIL_END
