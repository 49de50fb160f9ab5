// The one way core loops run over image rows in parallel (TBB). Each row is written by exactly one call of
// row(y) and rows are independent, so results do not depend on scheduling (deterministic).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace hf {

template <class RowFn>
void parallel_for_rows(int height, RowFn row) {
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y != rows.end(); ++y) row(y);
  });
}

}  // namespace hf
