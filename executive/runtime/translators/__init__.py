"""The translator plug-ins that come with dura (entry-point group ``dura.translators``)."""
