from rlcontroller.cli import main

main()
