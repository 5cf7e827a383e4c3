#!/usr/bin/env python3
"""X on
127.0.0.1, a port the system picks, until stdin closes: what `plc-conformance hil probe` asks to
judge the requests the server decodes by the MC protocol's rules.

    .venv-adapters/bin/python adapters/python/tools/virtual_plc_server.py
    # prints: listening on 127.0.0.1:PORT
"""
import sys

from virtual_plc import Memory, Server

server = Server(host="127.0.0.1", port=0, profile="Q", memory=Memory("Q"))
server.start()
host, port = server.address[:2]
print("listening on %s:%d" % (host, port), flush=True)
try:
    sys.stdin.read()
finally:
    server.stop()
