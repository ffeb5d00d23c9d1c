#pragma once

// Issue 41's memory attacks on a far-daemon, measured for bench/RESULTS.md (parts h, i and j of
// far_hardening_study):
//   (h) hoarding: a client opens sessions one after another, keeps each segment's descriptor
//       and closes the session; what the kept descriptors, the daemon and the system hold;
//   (i) a client killed while its step runs: how long the daemon keeps its segment (mapped,
//       and its memory allocated) and its resident size;
//   (j) a flood of large (60 KB) datagrams on the daemon's request channels: the daemon's
//       resident size before, at the end of the flood, and once it has drained it.

#include <sys/types.h>

#include <cstdint>
#include <string>
#include <vector>

#include "study_daemon.h"

namespace far::study {

/// A field of /proc/meminfo ("Shmem", "MemAvailable", ...) in KiB, or -1.
int64_t MemInfoKiB(const std::string& field);

/// The memory a descriptor's file has allocated (st_blocks * 512) and its size, in bytes.
struct FileBytes {
  int64_t allocated = 0;
  int64_t size = 0;
};
FileBytes BytesOf(int fd);

/// The session segment `name` ("far-session-<id>") as the process `pid` maps it: whether it
/// is mapped, and the bytes its memory file has allocated (read through /proc/<pid>/map_files,
/// which needs root; -1 when it cannot be read).
struct MappedSegment {
  bool mapped = false;
  int64_t allocated = -1;
};
MappedSegment SegmentOf(pid_t pid, const std::string& name);

struct HoardReport {
  int opened = 0;
  int refusals = 0;            ///< busy or limit_exceeded answers, retried
  double seconds = 0;          ///< opening and closing all of them
  FileBytes kept;              ///< summed over the kept descriptors, once the sessions closed
  int sessions_open = -1;      ///< the daemon's count after they closed
  int64_t rss_before = 0;      ///< daemon VmRSS, KiB
  int64_t rss_after = 0;       ///< daemon VmRSS once the sessions closed, KiB
  int64_t shmem_before = 0;    ///< system Shmem (/proc/meminfo), KiB
  int64_t shmem_after = 0;     ///< ... once the sessions closed (descriptors still kept)
  int64_t shmem_released = 0;  ///< ... once the descriptors were closed too
  std::string error;           ///< why it stopped early ("" when it did not)
};

/// (h) Opens `sessions` sessions by hand on the daemon's socket (the protocol, not far::Client,
/// which closes the descriptor), keeps each segment's descriptor and closes the connection;
/// measures once the daemon shows no session, then closes the descriptors.
HoardReport HoardSegments(const StudyDaemon& daemon, int sessions);

struct KilledClientReport {
  int64_t session_id = 0;
  std::string segment;
  double step_seconds_before_kill = 0;  ///< how long the step had run when the client died
  double freed_after_s = -1;     ///< until the segment's memory was gone (allocated 0 or unmapped)
  double unmapped_after_s = -1;  ///< until the daemon unmapped the segment
  int64_t allocated_at_kill = -1;          ///< the segment's allocated bytes when the client died
  int64_t rss_at_kill = 0, rss_after = 0;  ///< daemon VmRSS at the kill and as it unmapped, KiB
  std::string error;
};

/// (i) Runs `self` in kKilledClientFlag mode: it opens a session, uploads a scene of about
/// `triangles` triangles and steps it with `method` at `resolution`; `kill_after_s` after the
/// step was sent, it is killed with SIGKILL. When `neighbour_triangles` > 0, another client
/// (not killed) steps a scene of that size the same way first, so that the killed client's
/// step and its clean-up wait for the GL views of another session. Watches the daemon for up
/// to `watch_s` seconds.
struct KilledClientSetup {
  int64_t triangles = 20'000;
  int64_t neighbour_triangles = 200'000;
  std::string method = "far";
  int resolution = 1024;
  double kill_after_s = 2;
  double watch_s = 120;
};
KilledClientReport KillClientMidStep(const StudyDaemon& daemon, const std::string& self,
                                     const KilledClientSetup& setup);
inline constexpr const char* kKilledClientFlag = "--client-to-kill";
/// The child's main: argv = self, flag, socket, triangles, method, resolution. Prints
/// "<session id> <segment name>" once the scene is uploaded, then "stepping", then steps.
int KilledClientMain(int argc, char** argv);

struct BigFloodReport {
  int64_t sent = 0;
  int64_t bytes = 0;  ///< per datagram
  double seconds = 0;
  int64_t rss_before = 0, rss_end = 0, rss_after = 0;  ///< daemon VmRSS, KiB
  int64_t anon_before = 0, anon_after = 0;             ///< daemon RssAnon, KiB
  std::string error;
};

/// (j) Publishes `bytes`-byte datagrams of random bytes on the daemon's session request
/// channels (as fast as one thread can, for `seconds`), then waits `settle_s` for the daemon to
/// drain them.
BigFloodReport FloodLargeDatagrams(const StudyDaemon& daemon, int64_t bytes, double seconds,
                                   double settle_s);

/// The markdown sections of (h), (i) and (j) for bench/RESULTS.md.
void PrintHoarding(const HoardReport& report, int sessions);
void PrintKilledClient(const KilledClientReport& report, const KilledClientSetup& setup);
void PrintLargeFlood(const BigFloodReport& report);

}  // namespace far::study
