from wheelsoil.cli import main

raise SystemExit(main())
