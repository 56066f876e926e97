"""`python -m suctionbench`: the same command line as the `suctionbench` script."""

from suctionbench.cli import main

if __name__ == "__main__":
    main()
