"""HTTP API of the console: one router per resource (see ``app.server.create_app``)."""
