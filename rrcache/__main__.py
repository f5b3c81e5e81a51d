from rrcache.cli import main

main()
