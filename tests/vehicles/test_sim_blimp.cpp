// The simulated blimp's contacts with the ground and the buildings.
#include <catch2/catch.hpp>
