// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.ctre.phoenix6.configs;
public class TalonFXConfigurator { public Object apply(Slot0Configs configs) { return null; } }
