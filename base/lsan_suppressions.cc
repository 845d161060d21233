// LeakSanitizer's suppressions for the address-sanitizer build (README,
// "Sanitizer build"): leaks inside the system's libraries, not pointbake's,
// one pattern each with its reason. Linked into the test binaries and
// `pointbake` only when PB_SANITIZE has address (CMakeLists.txt); the
// runtime asks for this function at start, so ctest needs no LSAN_OPTIONS.
extern "C" const char* __lsan_default_suppressions() {
  return
      // PCL 1.13's Poisson allocates its B-spline dot tables (64,516 bytes,
      // once per process) and never frees them: implementations_test's PCL
      // Poisson runs report it from libpcl_surface.so.
      "leak:pcl::poisson::BSplineData*::setDotTables\n";
}
