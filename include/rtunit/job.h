// Ray and hit records of the RT-unit peripheral (rtunit/rtu_regs.h) from C++, and the reference
// the peripheral's results are checked against: the functional model of the RT unit, answering
// ray records with hit records as the peripheral writes them. Plain C++ (no SystemC).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "export.h"
#include "rtu_regs.h"

namespace rtu {

// A ray record (all reserved fields 0). `any_hit`: the first hit found, not the closest.
RTUNIT_API rtu_ray make_ray_record(const float org[3], const float dir[3], float tnear, float tfar, bool any_hit = false, uint32_t user = 0);

// What a ray record asks for, as the unit reads it.
enum class RecordTraversal : uint8_t { Dfs = 0, Bfs = 1 };

// The hit records of `count` ray records at `rays` (`ray_stride` bytes apart) traced through the
// BVH image of `bvh_size` bytes at `bvh`: bit for bit what the peripheral writes, whatever its
// fidelity. Ray i's hit is element i. A ray the ray-file contract calls invalid, or with a
// reserved flag bit set, is answered as an invalid-ray miss. Throws std::invalid_argument for an
// image that is not a BVH image (its header, or a node no encoder makes), and std::out_of_range /
// std::length_error for one whose nodes point outside it or into a cycle.
RTUNIT_API std::vector<rtu_hit> reference_hits(const uint8_t* bvh, size_t bvh_size, const uint8_t* rays, uint32_t count,
                                               uint32_t ray_stride = sizeof(rtu_ray), RecordTraversal order = RecordTraversal::Dfs);

}  // namespace rtu
