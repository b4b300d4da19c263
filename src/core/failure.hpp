// SPDX-License-Identifier: MIT
// The one exception type the core throws. The C boundary (src/capi) maps each kind to a status code;
// nothing below src/capi knows about C status numbers.
#pragma once

#include <stdexcept>
#include <string>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

enum class ErrorKind {
    InvalidArgument,
    NullArgument,
    EmptyInput,
    TooFewPoints,
    NonFinite,
    VoxelRange,
    StructSize,
    Cancelled,
    FeaturesMismatch,
    Io,
    Parse,
    UnsupportedFormat,
    Internal,
};

class Failure : public std::runtime_error {
public:
    Failure(ErrorKind kind, const std::string &message) : std::runtime_error(message), kind_(kind) {}
    ErrorKind kind() const noexcept { return kind_; }

private:
    ErrorKind kind_;
};

[[noreturn]] inline void fail(ErrorKind kind, const std::string &message) { throw Failure(kind, message); }

KISSM_DETAIL_END
