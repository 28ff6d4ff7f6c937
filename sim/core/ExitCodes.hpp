#pragma once
// The exit codes of every Ferro tool, one table for all stages:
//   0  done
//   1  internal error (a bug: please report the one-line message)
//   2  bad input: a scene key, an option or a file's content is wrong (the line says which)
//   3  the run failed: the simulation blew up or a stage could not finish a frame; files
//      written before it are kept
//   4  I/O: an input is missing or unreadable, or an output cannot be written

namespace ferro {

enum ExitCode { kExitOk = 0, kExitFailure = 1, kExitBadInput = 2, kExitSimulationFailed = 3, kExitIoError = 4 };

} // namespace ferro
