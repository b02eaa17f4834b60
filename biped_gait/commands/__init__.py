"""The verbs of ``biped-gait``, one module each (``cli_parser`` names the function that runs a
verb; ``cli`` imports it when the verb runs). Each takes the parsed arguments and returns the
exit status; a ``ValueError`` is bad input (one line, status 2)."""
