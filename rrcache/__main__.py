from rrcache.cli import main

# guarded: Dask's worker processes are spawned, and a spawned child imports the parent's main
# module (as __mp_main__) before it runs anything; unguarded, each worker would run the command
if __name__ == "__main__":
    main()
