"""dura's monitoring: observers, resource monitor, diagnosis and repair."""
