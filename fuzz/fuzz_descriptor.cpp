// A job descriptor from untrusted memory, as the SoC peripheral reads it at the start of a chain
// (platforms/peripheral.cpp): its magic, its fields (check_job_fields), then the BVH image and
// the ray records it points to, answered functionally (reference_hits). Input: the descriptor's
// 64-byte job half (what the unit reads; the completion half is the unit's to write), then the bytes of a RAM mapped at kRamBase (addresses outside it are a memory fault,
// as on a platform's bus). A bad descriptor must end in an error code or one of reference_hits's
// documented exceptions, never a crash, undefined behaviour, a hang or an allocation of its sizes.
#include <cstring>
#include <stdexcept>

#include <rtunit/job.h>

#include "model/job_records.h"

namespace {
constexpr uint64_t kRamBase = 0x1000;
constexpr uint32_t kMaxRays = 64;  // a short input stays short: the rest is the same code again
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    constexpr size_t kJobHalf = 64;
    if (size < kJobHalf) return 0;
    rtu_job_desc d{};
    std::memcpy(&d, data, kJobHalf);
    if (d.magic != RTU_DESC_MAGIC) return 0;  // RTU_ERR_BAD_DESC_MAGIC
    const rtu::JobSpec j = rtu::job_of_descriptor(d);
    if (rtu::check_job_fields(j).code) return 0;
    const uint8_t* ram = data + kJobHalf;
    const uint64_t ram_size = size - kJobHalf;
    // [base, base + bytes) inside the RAM, without overflow: else RTU_ERR_MEM_FAULT.
    const auto mapped = [&](uint64_t base, uint64_t bytes) {
        return base >= kRamBase && base - kRamBase <= ram_size && bytes <= ram_size - (base - kRamBase);
    };
    const uint32_t rays = std::min(j.ray_count, kMaxRays);
    if (!mapped(j.bvh_base, j.bvh_size)) return 0;
    if (rays && !mapped(j.ray_base, uint64_t(rays - 1) * j.ray_stride + sizeof(rtu_ray))) return 0;
    try {
        const uint8_t* ray_bytes = rays ? ram + (j.ray_base - kRamBase) : ram;  // no rays: ray_base is never read
        (void)rtu::reference_hits(ram + (j.bvh_base - kRamBase), j.bvh_size, ray_bytes, rays, j.ray_stride);
    } catch (const std::invalid_argument&) {  // not a BVH image: RTU_ERR_BAD_BVH
    } catch (const std::out_of_range&) {      // a node outside the image: RTU_ERR_BVH_OUT_OF_RANGE
    } catch (const std::length_error&) {      // a cycle among the nodes: RTU_ERR_BAD_BVH
    }
    return 0;
}
