// The proxy batch kernel (proxy_batch_kernel.h) built for the default target (SSE2 on x86-64).
#define PROXY_BATCH_ISA generic
#include "proxy_batch_kernel.h"
