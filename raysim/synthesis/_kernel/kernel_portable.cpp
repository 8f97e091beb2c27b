// Portable copy of the kernel (compiled for the extension's -march baseline).
#define KERNEL_NS portable
#define KERNEL_VBYTES 16
#include "kernel_impl.h"
namespace kernel {
void spread_portable(const Params& P) { portable::spread(P); }
}
