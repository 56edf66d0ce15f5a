"""Send a mail over SMTP."""

from __future__ import annotations

import smtplib
from email.message import EmailMessage

from knowledge.yamlsource import Section
from monitoring.repair.action import Action, ActionContext, Firing


class MailAction(Action):
    """Mail ``content`` to ``to_address`` through ``host:port`` (STARTTLS and login optional)."""

    type = "mail"

    def __init__(
        self,
        *,
        host: str,
        port: int,
        sender: str,
        recipients: tuple[str, ...],
        subject: str,
        content: str,
        login: tuple[str, str] | None,
        starttls: bool,
        timeout: float,
    ) -> None:
        super().__init__(timeout)
        self.host, self.port = host, port
        self.sender, self.recipients = sender, recipients
        self.subject, self.content = subject, content
        self.login, self.starttls = login, starttls

    @classmethod
    def configure(cls, entry: Section, timeout: float) -> Action:
        host = entry.text("host", "localhost") or "localhost"
        port = entry.integer("port", 25, minimum=1)
        sender = cls._require(entry, "from_address")
        recipients = entry.texts("to_address", required=True)
        subject = entry.text("subject", "dura: rule $rule fired") or ""
        content = entry.text("content", "Rule $rule fired. Possibly faulty: $faulty.") or ""
        username, password = entry.text("username"), entry.text("password")
        login = (username, password or "") if username else None
        return cls(
            host=host,
            port=port,
            sender=sender,
            recipients=recipients,
            subject=subject,
            content=content,
            login=login,
            starttls=entry.flag("starttls", False),
            timeout=timeout,
        )

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
