// SPDX-License-Identifier: BSD-3-Clause
#include "stopSignal.hpp"

#include <unistd.h>

#include <csignal>

namespace offline {

namespace {

// The signal that asked the run to stop (0: none). A signal handler can only set a flag
// of this type, so this one piece of state is global; the frame loop polls it between frames.
volatile std::sig_atomic_t requestedSignal = 0;

extern "C" void requestStop(int signal) {
  requestedSignal = signal;
  // write() is async-signal-safe; the handler was installed with SA_RESETHAND, so a
  // second signal ends the process at once (finished frames are safe either way).
  static constexpr char message[] =
      "\nofflineSimulator: stopping after the current frame (send the signal again to stop at once)\n";
  const ssize_t ignored = ::write(STDERR_FILENO, message, sizeof(message) - 1);
  static_cast<void>(ignored);
}

}  // namespace

void installStopHandlers() {
  struct sigaction action {};
  action.sa_handler = requestStop;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  ::sigaction(SIGINT, &action, nullptr);
  ::sigaction(SIGTERM, &action, nullptr);
}

int stopSignal() { return static_cast<int>(requestedSignal); }

const char* signalName(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    default:
      return "a signal";
  }
}

std::string resumeCommand(int argc, char** argv) {
  std::string command;
  bool hasResume = false;
  for (int i = 0; i < argc; ++i) {
    const std::string argument = argv[i];
    hasResume = hasResume || argument == "--resume";
    if (i > 0) command += ' ';
    if (!argument.empty() &&
        argument.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_./=+:,") ==
            std::string::npos) {
      command += argument;
    } else {
      command += '\'';
      for (const char c : argument) {
        if (c == '\'') {
          command += "'\\''";
        } else {
          command += c;
        }
      }
      command += '\'';
    }
  }
  if (!hasResume) command += " --resume";
  return command;
}

}  // namespace offline
