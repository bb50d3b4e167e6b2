#pragma once
// Physical and numerical constants shared by every folder.

namespace chlorovdb {

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kInvPi = 0.31830988618379067154f;
inline constexpr float kInv2Pi = 0.15915494309189533577f;
inline constexpr float kInv4Pi = 0.07957747154594766788f;
inline constexpr float kLn10 = 2.30258509299404568402f;
inline constexpr float kInfinity = 1e30f;  // finite on purpose: inf*0 would make NaN.

// Offset that lifts a spawned ray off its surface, scaled by the hit distance
// and the coordinates' magnitude so scenes far from the origin stay robust.
inline constexpr float kRayEpsilon = 1e-4f;

}  // namespace chlorovdb
