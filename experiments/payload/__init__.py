"""The payload sweep: payload mass x position x command, with its checks and reports."""
