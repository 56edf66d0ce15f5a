"""dura's knowledge: robot descriptions, PDDL domains and the knowledge base."""
