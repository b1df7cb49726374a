// The Catch2 runner, compiled once; the test files include only catch.hpp's declarations.
#define CATCH_CONFIG_MAIN
#include <catch2/catch.hpp>
