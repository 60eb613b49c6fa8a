"""The twin as a VDA 5050 2.0 vehicle on MQTT: orders in; state, visualization, connection, factsheet out."""
