#include "far/gpu/gl_lock.h"

namespace far {

std::unique_lock<std::recursive_mutex> LockGl() {
  static std::recursive_mutex mutex;
  return std::unique_lock(mutex);
}

}  // namespace far
