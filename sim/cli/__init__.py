"""The `cablecheck` command line: arguments, commands, what is printed and the exit statuses.

`main` (`main`, one function per command), `args` (the parser), `printing`
(progress bars and summaries).

This package computes nothing itself; it calls the stages and prints.
"""
