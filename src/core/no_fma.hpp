// OCCTRACK_NO_FMA_CONTRACTION: no fused multiply-add contraction from where it stands to the end of the
// file (private to the run-time library). Put it after a file's includes, so that it covers the file's own
// functions only.
//
// Why: code that decides on thresholds (the scenario generator: a grid cell free or not, a candidate clear
// or not) must give the same answer whether or not the build targets an instruction set with FMA
// (OCCTRACK_NATIVE). GCC contracts a * b + c into one rounding by default (-ffp-contract=fast), so the last
// bit, and then the decision, would depend on the build.
#pragma once

#if defined(__clang__)
#define OCCTRACK_NO_FMA_CONTRACTION _Pragma("clang fp contract(off)")
#elif defined(__GNUC__)
#define OCCTRACK_NO_FMA_CONTRACTION _Pragma("GCC optimize(\"fp-contract=off\")")
#else
#define OCCTRACK_NO_FMA_CONTRACTION
#endif
