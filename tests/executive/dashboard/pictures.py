"""Reading the SVG pictures back: they are XML, so tests look at what they show."""

from __future__ import annotations

import xml.etree.ElementTree as ET

SVG = "{http://www.w3.org/2000/svg}"


def parse(picture: str) -> ET.Element:
    """The picture's root element (it must be well-formed XML and an SVG document)."""
    root = ET.fromstring(picture.encode())  # noqa: S314 - dura's own picture
    assert root.tag == f"{SVG}svg"
    return root


def groups(root: ET.Element, css_class: str) -> list[ET.Element]:
    """The ``<g>`` elements whose class list has ``css_class``."""
    return [g for g in root.iter(f"{SVG}g") if css_class in (g.get("class") or "").split()]


def texts(element: ET.Element) -> list[str]:
    """Every line of text drawn inside an element (tooltips not included)."""
    return [t.text or "" for t in element.iter(f"{SVG}text")]


def tooltip(element: ET.Element) -> str:
    found = element.find(f"{SVG}title")
    return "" if found is None else found.text or ""
