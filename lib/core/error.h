// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! The library's exception types (a small hierarchy, as pmp's exceptions.h) and
//! assertion macros (as geogram's assert.h).

#include <stdexcept>
#include <string>

namespace nurbsfront {

//! Bad input or options at a public entry point; thrown before any work is done.
class InvalidInput : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

//! A file could not be read or written, or its content is malformed.
class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

//! The mesh has a topology the operation cannot handle (non-manifold, open, ...).
class TopologyError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

//! A numerical solver failed (singular system, no convergence).
class SolverError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

//! A broken internal invariant (a bug in nurbsfront, never the user's input).
class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

namespace detail {
[[noreturn]] void assertion_failed(const char* condition, const char* file, int line);
}  // namespace detail

}  // namespace nurbsfront

//! Cheap invariant check, always on: throws InternalError when violated.
#define NURBSFRONT_ASSERT(condition)                                                     \
  do {                                                                                  \
    if (!(condition)) ::nurbsfront::detail::assertion_failed(#condition, __FILE__, __LINE__); \
  } while (false)

//! Expensive invariant check, only in debug builds (NDEBUG not defined).
#ifdef NDEBUG
#define NURBSFRONT_DEBUG_ASSERT(condition) \
  do {                                     \
  } while (false)
#else
#define NURBSFRONT_DEBUG_ASSERT(condition) NURBSFRONT_ASSERT(condition)
#endif
