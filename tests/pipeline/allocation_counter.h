#pragma once
// Counts every operator new of the test executable (allocation_counter.cc replaces the global
// operator new and delete): tests read it around code that must not allocate.

#include <cstdint>

namespace gk::test {

int64_t allocations_so_far();

}  // namespace gk::test
