"""Error types that map onto the CLI's exit codes (2 = bad input, 1 = internal failure)."""


class InputError(ValueError):
    """Bad user input: a missing or malformed file, an absurd value, an unknown name.

    The message must name the offending input and say what is wrong with it, in one line;
    the CLI prints it and exits with code 2.
    """
