// The proxy batch kernel (proxy_batch_kernel.h) built for the default target: two doubles a vector,
// as SSE2 (x86-64's baseline) holds them (four spill its 16 registers; docs/performance.md).
#define PROXY_BATCH_ISA generic
#define PROXY_BATCH_WIDTH 2
#include "proxy_batch_kernel.h"
