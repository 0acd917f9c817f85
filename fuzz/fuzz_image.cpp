// A BVH image and ray records from untrusted memory, as the SoC peripheral reads them from a
// virtual platform's RAM and answers them functionally before anything else (reference_hits,
// platforms/peripheral.cpp). Input: a 4-byte little-endian image length, the image, then 48-byte
// ray records (at most 64). A broken image must give one of the documented exceptions, never a
// crash, undefined behaviour or a hang.
#include <cstring>
#include <stdexcept>

#include <rtunit/job.h>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 4) return 0;
    uint32_t len = 0;
    std::memcpy(&len, data, 4);
    const size_t image = std::min<size_t>(len, size - 4);
    const size_t rays = std::min<size_t>((size - 4 - image) / sizeof(rtu_ray), 64);
    try {
        (void)rtu::reference_hits(data + 4, image, data + 4 + image, uint32_t(rays));
    } catch (const std::invalid_argument&) {  // not a BVH image
    } catch (const std::out_of_range&) {      // a node outside the image
    } catch (const std::length_error&) {      // a cycle among the nodes
    }
    return 0;
}
