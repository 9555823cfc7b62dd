"""One router per resource; :func:`modd_backend.app.create_app` lists them."""
