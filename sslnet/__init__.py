"""Network facts and socket helpers shared by fieldsim, larcmacs_relay and the backend."""
