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
#ifndef vuSolverThreads_h
#define vuSolverThreads_h

namespace vu {
/** Holds the threads behind a sparse factorisation to the machine's cores while it lives,
 * and restores the previous settings afterwards.
 *
 * - BLAS on the calling thread alone. CHOLMOD's supernodal factorisation spends its time in
 *   many small dense BLAS calls. A multithreaded BLAS (OpenBLAS, Debian's libblas.so.3
 *   alternative when installed) forks and joins its threads for each of them; on an idle
 *   machine that gains 10-15 % over one thread, but as soon as any other process shares the
 *   cores each join waits for a descheduled thread, and the 1M-vertex flattening took 70 s
 *   instead of 9 s (measured with two low-priority busy loops beside it). A user who sets
 *   OPENBLAS_NUM_THREADS keeps that choice.
 * - OpenMP teams no larger than the free cores. CHOLMOD opens an OpenMP parallel region per
 *   supernode with a team size fixed at build time (4 in Debian's SuiteSparse 5), whatever
 *   OMP_NUM_THREADS says; on 2 cores the extra threads are descheduled at every region's
 *   barrier, and the factorisation of the 1M-vertex roll spent half its time in the kernel
 *   (1.3 million futex calls; 6.4 s, against 3.3 s with teams of 2). OpenMP's dynamic
 *   adjustment (`omp_set_dynamic`) lets the runtime shrink each team to the cores not
 *   already busy. A user who sets OMP_DYNAMIC or OMP_THREAD_LIMIT keeps that choice.
 *
 * Both runtimes are looked up among the libraries already loaded (as CHOLMOD's
 * dependencies): the library links neither. Without them this does nothing. */
class SolverThreads
{
public:
  SolverThreads();
  ~SolverThreads();
  SolverThreads(const SolverThreads &) = delete;
  SolverThreads &
  operator=(const SolverThreads &) = delete;

private:
  void (*m_SetBlasThreads)(int){ nullptr };
  int m_PreviousBlasThreads{ 0 };
  void (*m_SetDynamic)(int){ nullptr };
  int m_PreviousDynamic{ 0 };
};
} // namespace vu

#endif
