// Portable copy of the kernel (compiled for the extension's -march baseline).
#define RT_NS portable
#include "rt_impl.h"
namespace rt {
void project_portable(const Params& P) { portable::project(P); }
}
