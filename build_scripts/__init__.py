"""Builds the FMUs (pythonfmu) and post-processes their modelDescription.xml."""
