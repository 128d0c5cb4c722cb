#pragma once

#include <cstddef>
#include <vector>

namespace sunlapse {

// Asks the kernel to back the whole 2 MB pages inside [data, data + bytes)
// with huge pages (Linux, where transparent huge pages are "madvise" or
// "always"; elsewhere nothing). Call it before the first write: on virtual
// machines a first write to a 4 kB page costs several microseconds, and a
// buffer of tens of MB written once pays that thousands of times (at 1080p
// the tracker's ground map: 40 ms of a run's fixed costs). Returns the bytes
// advised (0 when none: a buffer under 2 MB, or no such kernel).
size_t AdviseHugePages(void* data, size_t bytes);

// Reserves room for n elements and advises it, for a vector about to be
// written whole; a vector that already holds n keeps its pages.
template <class T>
void ReserveHuge(std::vector<T>* v, size_t n) {
  if (v->capacity() >= n) return;
  v->reserve(n);
  AdviseHugePages(v->data(), n * sizeof(T));
}

}  // namespace sunlapse
