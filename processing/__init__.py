"""wheelsoil.processing"""
