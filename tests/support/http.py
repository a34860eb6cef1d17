"""Requests to the explorer's server sent as written, and its one-line refusals."""

import http.client


def get(server, path: str, host: str | None = None, method: str = "GET"):
    """(status, body text) of a request sent as written (no normalisation of the path)."""
    h, port = server.server_address[:2]
    conn = http.client.HTTPConnection(h, port, timeout=120)
    conn.putrequest(method, path, skip_host=True, skip_accept_encoding=True)
    conn.putheader("Host", host or f"{h}:{port}")
    conn.endheaders()
    response = conn.getresponse()
    body = response.read().decode("utf-8", "replace")
    conn.close()
    return response.status, body


def refused(server, path: str, status: int, reason: str) -> str:
    """The body of a request the server refuses with ``status``: one line, naming the
    status and ``reason``, no traceback."""
    got, body = get(server, path)
    assert got == status, body
    assert body.count("\n") == 1 and reason in body and "Traceback" not in body, body
    return body
