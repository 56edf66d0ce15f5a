"""Who may open the dashboard.

When the robot has bus credentials, every visitor must show them, from this machine
too (another local user cannot read the user-only credentials file, and so cannot act
on the robot): HTTP basic authentication as the ``operator`` with its password (from
the robot's credentials file, :mod:`executive.bus.security`), or a token derived from
that password (:meth:`Access.token`, in the link the dashboard prints at start, given
once as ``?token=`` and then kept in a cookie). A robot without credentials has a
loopback dashboard only, open to this machine.

Whatever the client, a request must name the dashboard by a host on its allow-list —
loopback names, an IP address, the names given with ``--allow-host``, and beyond
loopback this machine's own names — so that a web page elsewhere cannot reach the
dashboard by renaming itself (DNS rebinding); and changes (POST) must come from the
dashboard's own page.
"""

from __future__ import annotations

import base64
import binascii
import hashlib
import hmac
import ipaddress
from collections.abc import Mapping
from dataclasses import dataclass

from executive.bus.security import OPERATOR

COOKIE = "dura_dashboard"
DEFAULT_HOST = "127.0.0.1"  # loopback: this machine only
DEFAULT_PORT = 8470


def is_loopback(host: str) -> bool:
    """Whether ``host`` (a name or an address, IPv6 in brackets or not) is this machine
    by loopback."""
    host = host.strip().strip("[]").lower()
    if host == "localhost" or host.endswith(".localhost"):
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def host_name(header: str) -> str:
    """The host of a ``Host`` header, without its port."""
    header = header.strip()
    if header.startswith("["):
        return header[1 : header.find("]")] if "]" in header else header
    return header.rsplit(":", 1)[0] if header.count(":") == 1 else header


@dataclass(frozen=True)
class Access:
    """The dashboard's access rule.

    Args:
        host: the address the dashboard listens on.
        password: the operator's bus password (``None``: the robot has no credentials,
            so only loopback clients may come in).
        names: the host names (``Host`` header) it answers to beyond loopback names and
            IP addresses (a loopback dashboard answers to loopback names only).
    """

    host: str
    password: str | None = None
    names: tuple[str, ...] = ()  # the host names a request may use, beyond the loopback ones

    @property
    def local_only(self) -> bool:
        return is_loopback(self.host)

    @property
    def token(self) -> str | None:
        """A token derived from the operator's password, for a link to the page."""
        if self.password is None:
            return None
        digest = hmac.new(self.password.encode(), b"dura dashboard", hashlib.sha256)
        return digest.hexdigest()[:40]

    def host_allowed(self, header: str) -> bool:
        """Whether a request's ``Host`` header names this dashboard: a loopback name, or
        (beyond loopback) an IP address or a name of the allow-list."""
        host = host_name(header).strip("[]").lower()
        if not host or is_loopback(host):
            return bool(host)
        if self.local_only:
            return False
        try:
            ipaddress.ip_address(host)
            return True  # no page renames itself to an address: rebinding needs a name
        except ValueError:
            return host.rstrip(".") in {n.lower().rstrip(".") for n in self.names}

    def allows(
        self,
        client: str | None,
        headers: Mapping[str, str],
        cookies: Mapping[str, str],
        token: str | None = None,
    ) -> bool:
        """Whether a request may see the dashboard: with the operator's password (basic
        authentication) or the token; without credentials (the robot has none), a
        loopback client only."""
        if self.password is None:
            return client is not None and is_loopback(client)
        expected = self.token or ""
        for offered in (token, cookies.get(COOKIE)):
            if offered and hmac.compare_digest(offered.encode(), expected.encode()):
                return True
        authorization = headers.get("authorization", "")
        scheme, _, value = authorization.partition(" ")
        if scheme.lower() == "bearer":
            return hmac.compare_digest(value.strip().encode(), expected.encode())
        if scheme.lower() != "basic":
            return False
        try:
            user, _, password = base64.b64decode(value.strip()).decode().partition(":")
        except (binascii.Error, UnicodeDecodeError):
            return False
        return user == OPERATOR and hmac.compare_digest(password.encode(), self.password.encode())

    @staticmethod
    def same_origin(headers: Mapping[str, str]) -> bool:
        """Whether a change comes from the dashboard's own page: its ``Origin`` (when the
        browser sends one) is the host it asked."""
        origin = headers.get("origin")
        if origin is None:
            return True
        host = headers.get("host", "")
        return origin in (f"http://{host}", f"https://{host}")
