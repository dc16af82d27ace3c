// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.revrobotics.spark;
public enum ClosedLoopSlot { kSlot0, kSlot1, kSlot2, kSlot3 }
