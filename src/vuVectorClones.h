/*=========================================================================
 *
 *  Copyright NumFOCUS
 *
 *  Licensed under the Apache License, Version 2.0 (the "License");
 *  you may not use this file except in compliance with the License.
 *  You may obtain a copy of the License at
 *
 *         http://www.apache.org/licenses/LICENSE-2.0.txt
 *
 *  Unless required by applicable law or agreed to in writing, software
 *  distributed under the License is distributed on an "AS IS" BASIS,
 *  WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
 *  See the License for the specific language governing permissions and
 *  limitations under the License.
 *
 *=========================================================================*/
#ifndef vuVectorClones_h
#define vuVectorClones_h

// A function marked VU_VECTOR_CLONES is compiled twice on x86-64 with GCC, for AVX2 (8
// floats a vector) and for the baseline (SSE2, 4), and the loader picks the one the
// processor runs. Without FMA, both clones do the same operations in the same order: the
// same values, bit for bit.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#  define VU_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#  define VU_VECTOR_CLONES
#endif

#endif
