// Force-included into the fuzz build's sources (tests/fuzz/CMakeLists.txt): toml++'s internal
// assertions off, as in Debian's libtomlplusplus (built with NDEBUG), without defining
// NDEBUG, which would turn them into clang's __builtin_assume. See README.md.
#define TOML_ASSERT(expr) static_assert(true)
