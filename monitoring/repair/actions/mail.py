"""Send a mail over SMTP."""

from __future__ import annotations

import smtplib
from dataclasses import dataclass
from email.message import EmailMessage
from typing import Annotated

from knowledge.conventions import AtLeast, Key, OneOrMore, OrDefault, Required
from monitoring.repair.action import Action, ActionContext, Firing


@dataclass(frozen=True, kw_only=True)
class MailAction(Action):
    """Mail ``content`` to ``to_address`` through ``host:port`` (STARTTLS and login optional)."""

    type = "mail"
    host: Annotated[str, OrDefault()] = "localhost"
    port: Annotated[int, AtLeast(1)] = 25
    sender: Annotated[str, Key("from_address"), Required()] = ""
    recipients: Annotated[tuple[str, ...], Key("to_address"), OneOrMore(), Required()] = ()
    subject: str = "dura: rule $rule fired"
    content: str = "Rule $rule fired. Possibly faulty: $faulty."
    username: str | None = None
    password: str | None = None
    starttls: bool = False

    @property
    def login(self) -> tuple[str, str] | None:
        return (self.username, self.password or "") if self.username else None

    def _run(self, context: ActionContext, firing: Firing) -> None:
        message = EmailMessage()
        message["Subject"] = firing.fill(self.subject)
        message["From"] = self.sender
        message["To"] = ", ".join(self.recipients)
        message.set_content(firing.fill(self.content))
        with smtplib.SMTP(self.host, self.port, timeout=self.timeout) as smtp:
            if self.starttls:
                smtp.starttls()
            if self.login is not None:
                smtp.login(*self.login)
            smtp.send_message(message)

    def describe(self) -> str:
        return f"mail {', '.join(self.recipients)} via {self.host}:{self.port}"
