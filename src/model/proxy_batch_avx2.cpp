// The proxy batch kernel (proxy_batch_kernel.h) built for AVX2: this unit alone is compiled with
// -mavx2, and ProxyBatch calls it only where the CPU has AVX2.
#define PROXY_BATCH_ISA avx2
#define PROXY_BATCH_WIDTH 4
#include "proxy_batch_kernel.h"
