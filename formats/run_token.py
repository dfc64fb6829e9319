"""The run token: what a controller program presents before it sends a log over TCP.

``wirecal receive`` listens on a shop network; only a sender that knows the run's token
may deliver a log. The token is derived, not drawn, so that a program generated again and
a receiver started again agree without anything passing between them, and generated
programs stay the same bytes for the same inputs:

    token = HMAC-SHA256(key, "wirecal-run " + plan fingerprint), first 32 hex digits

``key`` is the robot file's ``[controller] key`` (a secret of the site: any 16 or more
printable characters). Without a key the token is the same function of the plan alone:
it keeps port probes, stray programs and programs of another plan out, but anyone holding
the plan file can compute it (:data:`NO_KEY` says so). The connection is plain TCP: the
token travels unencrypted, like the log.

The program's first line on the connection is ``# wirecal-token <token>`` (:data:`PREFIX`);
it is not part of the log and is not written to it.
"""

from __future__ import annotations

import hashlib
import hmac

from wirecal.solver.robot import Robot

PREFIX = "# wirecal-token "
"""The first line a sender writes, followed by the token."""
TOKEN_HEX = 32
MIN_KEY_CHARS = 16
NO_KEY = (
    "[controller] key is not set: the run token derives from the plan alone, so anyone "
    'with the plan file can send a log; set key = "…" (16 or more random characters, '
    "kept off shared copies) in the robot file and generate the programs again"
)


def run_token(robot: Robot, fingerprint: str) -> str:
    """Return the token of a run of the plan with ``fingerprint`` on ``robot``."""
    key = (robot.controller.key or "").encode("utf-8")
    message = f"wirecal-run {fingerprint}".encode()
    return hmac.new(key, message, hashlib.sha256).hexdigest()[:TOKEN_HEX]


def token_line(token: str) -> str:
    """Return the line a sender presents its token with."""
    return PREFIX + token


def presents(line: str, token: str) -> bool:
    """Whether ``line`` presents ``token`` (compared in constant time)."""
    return line.startswith(PREFIX) and hmac.compare_digest(line[len(PREFIX) :].strip(), token)
