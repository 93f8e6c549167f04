"""wheelsoil.model"""
