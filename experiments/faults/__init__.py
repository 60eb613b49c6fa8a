"""The fault study: what each firmware does under each fault."""
