// What librtunit exports: the library is built with hidden visibility, so only declarations
// marked RTUNIT_API are visible to a platform that links it (no absl, glm or internal symbols).
#pragma once

#if defined(__GNUC__) || defined(__clang__)
#define RTUNIT_API __attribute__((visibility("default")))
#else
#define RTUNIT_API
#endif
