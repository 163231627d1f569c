from chainrun.cli import main

main()
