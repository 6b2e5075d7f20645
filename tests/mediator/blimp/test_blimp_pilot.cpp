// The blimp course, its lap timer and the automatic pilot.
#include <catch2/catch.hpp>
