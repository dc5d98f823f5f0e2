"""Planning and running jobs: options, the content-addressed cache, the process core."""
