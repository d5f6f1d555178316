#pragma once
// The LCM channels of a hapsim run, one name each (issue 4). Message types in messages/*.lcm.

namespace hapsim::messages {

inline constexpr char kDeviceStateChannel[] = "DEVICE_STATE";    // device_state_t, 1 kHz
inline constexpr char kDeviceForceChannel[] = "DEVICE_FORCE";    // device_force_t, 1 kHz
inline constexpr char kContactModelChannel[] = "CONTACT_MODEL";  // contact_model_t, per frame
inline constexpr char kHapticStateChannel[] = "HAPTIC_STATE";    // haptic_state_t, 1 kHz
inline constexpr char kSimFrameChannel[] = "SIM_FRAME";          // sim_frame_t, per frame
inline constexpr char kRunInfoChannel[] = "RUN_INFO";            // run_info_t, at start

// Default transport: UDP multicast that stays on this machine (ttl=0), with a 4 MB receive
// buffer: an lcp contact model of ~220 rows is ~200 kB, sent in fragments that must all fit in
// the socket buffer at once (the kernel default, 208 kB, dropped the earlier 330 kB models).
inline constexpr char kDefaultLcmUrl[] = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

}  // namespace hapsim::messages
