// SPDX-License-Identifier: BSD-3-Clause
// A 64-bit FNV-1a hash of bytes: whether data is the same to the bit as before, cheaply (a
// benchmark's checksum of every frame, a filter's test of whether its input changed).
#pragma once

#include <cstddef>
#include <cstdint>

namespace md
{
class Fnv1a
{
public:
  void Add(const void* data, size_t bytes)
  {
    const auto* byte = static_cast<const unsigned char*>(data);
    for (size_t k = 0; k < bytes; ++k)
    {
      this->Hash = (this->Hash ^ byte[k]) * 1099511628211ULL;
    }
  }
  /// The bytes of a plain value (a number).
  template<typename T>
  void Add(const T& value)
  {
    this->Add(&value, sizeof(T));
  }
  std::uint64_t Value() const { return this->Hash; }

private:
  std::uint64_t Hash = 14695981039346656037ULL;
};
}
