// Whether this test binary was built with a sanitizer, for the few end-to-end
// tests whose sanity bounds on wall time must widen under one (ASan and TSan
// slow mapd 2-10x). Targets themselves are checked by benchmarks, not here.
#ifndef MAPD_TESTS_COMMON_SANITIZERS_H_
#define MAPD_TESTS_COMMON_SANITIZERS_H_

namespace mapd::testing {

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

}  // namespace mapd::testing

#endif  // MAPD_TESTS_COMMON_SANITIZERS_H_
