#include "haptel/interfaces/interface.hpp"

#include <algorithm>
#include <cmath>

namespace haptel::interfaces {

TreadCommand Mix(double forward, double turn) {
  TreadCommand cmd{forward - turn, forward + turn};
  const double largest = std::max({1.0, std::abs(cmd.left), std::abs(cmd.right)});
  cmd.left /= largest;
  cmd.right /= largest;
  return cmd;
}

}  // namespace haptel::interfaces
