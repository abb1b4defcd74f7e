// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How offlineSimulator stops on SIGINT and SIGTERM: after the current frame, with a
// checkpoint, and a command that continues the run.

#include <string>

namespace offline {

/// Makes SIGINT and SIGTERM ask the run to stop after the current frame (a second one ends
/// the process at once).
void installStopHandlers();
/// The signal that asked the run to stop on this process, 0 while none did.
int stopSignal();
/// "SIGINT", "SIGTERM", or "a signal".
const char* signalName(int signal);
/// The command to continue an interrupted run: this one (argv, shell-quoted), with
/// --resume added.
std::string resumeCommand(int argc, char** argv);

}  // namespace offline
