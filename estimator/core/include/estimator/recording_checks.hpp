#pragma once
// What a recording's header and time column say about likely mistakes: a
// header word that is not a contract column but nearly one ("tauin" for
// tau_in), words no reader of ours knows, and times that look like
// milliseconds. Warnings, not errors: extra columns are allowed by the
// contract and a 1 Hz recording in seconds is possible; but each of these
// has silently changed a result (tau_in taken from T1/T3 instead, "no
// motion: 0 velocity reversals") without a word.

#include <string>
#include <string_view>
#include <vector>

#include "estimator/table.hpp"

namespace tsmh::estimator {

/// The contract column `word` most likely meant (case, '_', '-' and one
/// wrong, missing or swapped letter forgiven; "time" -> "t"); empty when
/// none is that near, or when `word` is one.
std::string contract_column_for(std::string_view word);

/// One warning per header word that is neither a contract column nor a
/// column our own writers add (the virtual slave's truth columns, tsm
/// simulate's output), naming it and, when one is near, the column meant.
std::vector<std::string> header_warnings(const Table& table);

/// A warning when the time steps look like milliseconds (or a finer unit)
/// rather than seconds: median step >= 0.5 over at least 100 rows. Empty
/// otherwise.
std::string time_unit_warning(const std::vector<double>& t);

}  // namespace tsmh::estimator
