/* rtunit RT-unit peripheral: register map, job descriptor, ray and hit records.
 *
  * C11 (or C++11) for firmware, Linux user space and the virtual platform alike. All registers
 * are 32-bit little-endian in a 4 KiB aperture; the block decodes address & 0xFFF, so it works
 * behind routers that pass absolute or relative addresses. 64-bit values are LO/HI pairs (an
 * aligned 8-byte access reads or writes a pair at once). Reading a performance counter's LO
 * latches its HI. Layouts follow the reference design of an SoC peripheral (docs/peripheral.md says where
 * this implementation differs); they are version 1.0 of the interface (RTU_VERSION).
 */
#ifndef RTUNIT_RTU_REGS_H
#define RTUNIT_RTU_REGS_H

#include <stdint.h>

#define RTU_APERTURE_BYTES 0x1000u

#define RTU_ID_VALUE 0x31555452u  /* "RTU1" */
#define RTU_VERSION_VALUE 0x00010000u /* [31:16] major, [15:8] minor, [7:0] patch */

/* Register offsets. */
#define RTU_ID 0x000u
#define RTU_VERSION 0x004u
#define RTU_CONFIG0 0x008u /* [7:0] sms, [15:8] warp size, [23:16] warp buffer, [27:24] fidelity, [31:28] memory path */
#define RTU_CONFIG1 0x00Cu /* [3:0] traversal, [7:4] prefetcher, [31:8] core clock in MHz */
#define RTU_CTRL 0x010u
#define RTU_STATUS 0x014u
#define RTU_INT_STATUS 0x018u /* write 1 to clear */
#define RTU_INT_ENABLE 0x01Cu
#define RTU_INT_SET 0x020u /* write-only: write 1 to set an INT_STATUS bit */
#define RTU_ERR_CODE 0x024u
#define RTU_ERR_ADDR_LO 0x028u
#define RTU_ERR_ADDR_HI 0x02Cu
#define RTU_DESC_ADDR_LO 0x040u
#define RTU_DESC_ADDR_HI 0x044u
#define RTU_BVH_BASE_LO 0x048u
#define RTU_BVH_BASE_HI 0x04Cu
#define RTU_BVH_SIZE_LO 0x050u
#define RTU_BVH_SIZE_HI 0x054u
#define RTU_RAY_BASE_LO 0x058u
#define RTU_RAY_BASE_HI 0x05Cu
#define RTU_RAY_COUNT 0x060u
#define RTU_STRIDES 0x064u /* [15:0] ray stride, [31:16] hit stride (bytes; 0 means 48) */
#define RTU_HIT_BASE_LO 0x068u
#define RTU_HIT_BASE_HI 0x06Cu
#define RTU_JOB_FLAGS 0x070u
#define RTU_JOB_ID 0x074u
#define RTU_MAX_CHAIN 0x080u
#define RTU_PERF_CTRL 0x100u
#define RTU_PERF_BUSY_CYCLES 0x108u       /* LO; HI at +4 */
#define RTU_PERF_JOB_CYCLES 0x110u        /* last job: START (or descriptor fetch) to its last hit write */
#define RTU_PERF_TRAVERSAL_CYCLES 0x118u  /* last job: first trace taken to last ray retired */
#define RTU_PERF_RAYS 0x120u
#define RTU_PERF_HITS 0x128u
#define RTU_PERF_INVALID_RAYS 0x130u
#define RTU_PERF_NODES_VISITED 0x138u
#define RTU_PERF_NODE_FETCHES 0x140u
#define RTU_PERF_L1_ACCESSES 0x148u
#define RTU_PERF_L1_MISSES 0x150u
#define RTU_PERF_L2_ACCESSES 0x158u
#define RTU_PERF_L2_MISSES 0x160u
#define RTU_PERF_DRAM_READS 0x168u
#define RTU_PERF_PREFETCHES_SENT 0x170u
#define RTU_PERF_PREFETCHES_USEFUL 0x178u
#define RTU_PERF_MEM_BYTES_RD 0x180u
#define RTU_PERF_MEM_BYTES_WR 0x188u
#define RTU_SCRATCH 0x1F0u

/* CTRL */
#define RTU_CTRL_START (1u << 0)      /* self-clearing */
#define RTU_CTRL_ABORT (1u << 1)      /* self-clearing */
#define RTU_CTRL_SOFT_RESET (1u << 2) /* self-clearing; idle only */
#define RTU_CTRL_MODE_CHAIN (1u << 4) /* 0: the job in the JOB registers; 1: the chain at DESC_ADDR */

/* STATUS */
#define RTU_STATUS_BUSY (1u << 0)
#define RTU_STATUS_DONE (1u << 1)
#define RTU_STATUS_ERROR (1u << 2)
#define RTU_STATUS_ABORTED (1u << 3)
#define RTU_STATUS_START_IGNORED (1u << 4)
#define RTU_STATUS_ERR_CODE(s) (((s) >> 8) & 0xFFu)
#define RTU_STATUS_DESCS_DONE(s) (((s) >> 16) & 0xFFFFu)

/* INT_STATUS, INT_ENABLE, INT_SET; the line is OR(INT_STATUS & INT_ENABLE) */
#define RTU_INT_JOB_DONE (1u << 0)
#define RTU_INT_CHAIN_DONE (1u << 1)
#define RTU_INT_ERROR (1u << 2)
#define RTU_INT_ABORTED (1u << 3)
#define RTU_INT_ALL 0xFu

/* ERR_CODE */
#define RTU_ERR_NONE 0u
#define RTU_ERR_BAD_DESC_MAGIC 1u
#define RTU_ERR_BAD_BVH 2u          /* header magic or version, size < 64, or a node past the image */
#define RTU_ERR_BAD_ALIGN 3u        /* a base not aligned, or a stride < 48 or not a multiple of 16 */
#define RTU_ERR_MEM_FAULT 4u        /* a non-OK response on the memory socket (ERR_ADDR) */
#define RTU_ERR_BVH_CHANGED 5u      /* CHECK_BVH: a node the job read differs in memory from the image it traced (ERR_ADDR) */
#define RTU_ERR_BVH_OUT_OF_RANGE 6u /* traversal read past BVH_SIZE */
#define RTU_ERR_CHAIN_LOOP 7u       /* more than MAX_CHAIN descriptors */
#define RTU_ERR_BAD_FLAGS 8u        /* reserved flag bits set in JOB_FLAGS or a descriptor */
#define RTU_ERR_TOO_LARGE 9u        /* more than RTU_MAX_RAYS rays, or an image over RTU_MAX_BVH_BYTES */

/* What one job may ask for: the unit holds a job's rays, hits and image in its host memory. */
#define RTU_MAX_RAYS (1u << 22)
#define RTU_MAX_BVH_BYTES (4ull << 30)

/* PERF_CTRL */
#define RTU_PERF_ENABLE (1u << 0)
#define RTU_PERF_CLEAR (1u << 1) /* self-clearing */
#define RTU_PERF_FREEZE (1u << 2)

/* CONFIG0 [27:24] fidelity, [31:28] memory path */
#define RTU_FIDELITY_FUNCTIONAL 0u
#define RTU_FIDELITY_INTERVAL 1u
#define RTU_FIDELITY_LT 2u
#define RTU_FIDELITY_AT 3u
#define RTU_MEMORY_PRIVATE 0u
#define RTU_MEMORY_SHARED 1u

/* Job descriptor (CTRL.MODE = 1): 128 bytes, 64-byte aligned. Software writes the first 64
 * bytes; the unit writes the completion half, `status` last. */
#define RTU_DESC_MAGIC 0x314A5452u /* "RTJ1" */
#define RTU_JOB_IRQ_ON_DONE (1u << 0)
#define RTU_JOB_CHECK_BVH (1u << 1) /* private memory path: after tracing, every node read is read again and compared; shared: each sector read is compared (RTU_ERR_BVH_CHANGED) */
#define RTU_DESC_STATUS_DONE (1u << 31)
#define RTU_DESC_STATUS_ERROR (1u << 30)
#define RTU_DESC_STATUS_ABORTED (1u << 29)

#if defined(__GNUC__)
#define RTU_PACKED __attribute__((packed))
#else
#define RTU_PACKED
#endif

typedef struct RTU_PACKED rtu_job_desc {
    uint32_t magic;      /* RTU_DESC_MAGIC */
    uint32_t flags;      /* RTU_JOB_* */
    uint64_t bvh_base;   /* 64-byte aligned */
    uint64_t bvh_size;
    uint64_t ray_base;   /* 16-byte aligned */
    uint64_t hit_base;   /* 16-byte aligned */
    uint32_t ray_count;
    uint16_t ray_stride; /* 0 means 48 */
    uint16_t hit_stride; /* 0 means 48 */
    uint64_t next;       /* 0 ends the chain */
    uint32_t job_id;
    uint32_t reserved0;
    /* completion record, written by the unit */
    uint32_t status;     /* RTU_DESC_STATUS_*, [7:0] error code; written last */
    uint32_t rays;
    uint64_t job_cycles;
    uint64_t traversal_cycles;
    uint32_t hits;
    uint32_t invalid_rays;
    uint64_t nodes_visited;
    uint64_t node_fetches;
    uint32_t l1_misses;  /* saturating */
    uint32_t l2_misses;  /* saturating */
    uint64_t start_ps;   /* simulated time of the descriptor fetch, in ps */
} rtu_job_desc;

/* Ray record: 48 bytes, 16-byte aligned. */
#define RTU_RAY_ANY_HIT (1u << 0) /* 0: closest hit; any other bit set makes the ray invalid */
typedef struct RTU_PACKED rtu_ray {
    float org[3];
    float tnear;
    float dir[3];
    float tfar; /* +inf allowed */
    uint32_t flags;
    uint32_t user; /* copied to the hit record */
    uint32_t reserved[2];
} rtu_ray;

/* Hit record: 48 bytes, 16-byte aligned; hit i belongs to ray i. */
#define RTU_HIT_HIT (1u << 0)
#define RTU_HIT_INVALID_RAY (1u << 1)
typedef struct RTU_PACKED rtu_hit {
    uint32_t status;   /* RTU_HIT_* */
    float t;           /* in units of the ray's direction as given; -1 on a miss */
    uint32_t geom;     /* 0xFFFFFFFF on a miss */
    uint32_t prim;     /* 0xFFFFFFFF on a miss */
    float u, v;        /* barycentrics (triangles) */
    float ng[3];       /* world-space geometric normal, not normalised */
    uint32_t nodes_visited;
    uint32_t user;     /* from the ray */
    uint32_t reserved;
} rtu_hit;

#ifdef __cplusplus
static_assert(sizeof(rtu_job_desc) == 128, "rtu_job_desc is 128 bytes");
static_assert(sizeof(rtu_ray) == 48, "rtu_ray is 48 bytes");
static_assert(sizeof(rtu_hit) == 48, "rtu_hit is 48 bytes");
#else
_Static_assert(sizeof(rtu_job_desc) == 128, "rtu_job_desc is 128 bytes");
_Static_assert(sizeof(rtu_ray) == 48, "rtu_ray is 48 bytes");
_Static_assert(sizeof(rtu_hit) == 48, "rtu_hit is 48 bytes");
#endif

#endif /* RTUNIT_RTU_REGS_H */
