"""Exit codes of every ``mcrt`` command: one meaning each, everywhere."""

#: Success: the command did its work (images consistent, a report written).
EXIT_OK = 0
#: A check failed: images differ, a test was rejected, a submission scored below full marks in a batch.
EXIT_FAILED = 1
#: Unusable input: a bad scene file, an unreadable image, a bad option; the message names the file and the problem.
EXIT_UNUSABLE = 2
