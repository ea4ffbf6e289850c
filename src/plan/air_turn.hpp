#pragma once
/// @file The turn of the rotary axes between two passes, spread over the moves in the air.
///
/// Where a pass ends on other axes than the next one starts, the rotary axes must turn
/// somewhere in the chain of moves between them (retract, rise, traverse, descent). Rapids run
/// rest to rest with each joint on its own trapezoid (feed_schedule.hpp, rapid_time_s): a rapid
/// of linear time T lets a rotary joint (velocity limit v, acceleration limit a) travel
///   d(T) = v (T - v / a)  where T >= 2 v / a,   else  a T^2 / 4,
/// at no cost. Each rapid of the chain can so carry a share of the turn, its capacity
/// min over A and C of d(T) / |turn|; the turn is spread over the rapids in proportion to their
/// capacities. Where they add up to at least 1 the turn costs no time at all (on a machine
/// whose linear joints the turn does not move). best_turn_shares then improves the shares for
/// the machine's real joint times; the caller keeps the result only where it is faster than the
/// turn made in one move, and checks the new poses.

#include <functional>
#include <vector>

#include "taxopt/kinematics/feed_schedule.hpp"

namespace taxopt {

/// Distance a joint travels from rest to rest in `time_s` within its limits (per second units
/// of the limit); a joint without a velocity or acceleration limit: infinite.
double rest_to_rest_reach(double time_s, const JointLimit& limit);

/// The share of the turn each of m moves carries by its capacity (see the file comment): in
/// proportion to it where `rapid[k]`, none where not; the shares add up to 1. `linear_time_s[k]`
/// is move k's time without the turn. Empty when no rapid can carry any of the turn, or when
/// the turn is zero.
std::vector<double> spread_turn(const std::vector<double>& linear_time_s,
                                const std::vector<bool>& rapid, double turn_a_deg,
                                double turn_c_deg, const JointLimits& limits);

/// The shares of a turn over m moves (each >= 0, adding up to 1, 0 where !may_turn[k]) with
/// the least `time_of(shares)`: from each start, a pattern search that moves share between two
/// moves that may turn, in steps halving from 1/2 to 1/256. On a table-table machine the turn
/// also moves the linear joints (the part turns under the tool), which the capacities above do
/// not see: the caller's time_of times the joints themselves. The result is never slower than
/// the best start.
std::vector<double> best_turn_shares(
    const std::vector<std::vector<double>>& starts, const std::vector<bool>& may_turn,
    const std::function<double(const std::vector<double>&)>& time_of);

}  // namespace taxopt
