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
#ifndef vuBlasThreads_h
#define vuBlasThreads_h

namespace vu {
/** Runs the BLAS behind a sparse factorisation on the calling thread alone while it
 * lives, and restores the previous setting afterwards.
 *
 * CHOLMOD's supernodal factorisation spends its time in many small dense BLAS calls. A
 * multithreaded BLAS (OpenBLAS, Debian's libblas.so.3 alternative when installed) forks
 * and joins its threads for each of them; on an idle machine that gains 10-15 % over one
 * thread, but as soon as any other process shares the cores each join waits for a
 * descheduled thread, and the 1M-vertex flattening took 70 s instead of 9 s (measured
 * with two low-priority busy loops beside it). A user who sets OPENBLAS_NUM_THREADS keeps
 * that choice. Without OpenBLAS (the reference BLAS, or none) this does nothing. */
class SingleThreadedBlas
{
public:
  SingleThreadedBlas();
  ~SingleThreadedBlas();
  SingleThreadedBlas(const SingleThreadedBlas &) = delete;
  SingleThreadedBlas &
  operator=(const SingleThreadedBlas &) = delete;

private:
  void (*m_Set)(int){ nullptr };
  int m_Previous{ 0 };
};
} // namespace vu

#endif
